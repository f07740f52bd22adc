"""Export to JSONL and Parquet and import into a new session, on SQLite and PostgreSQL."""

import json

import pytest

from groupwise.storage import InvalidError
from groupwise.storage.counts import counts
from groupwise.storage.export import export_session, import_session
from groupwise.storage.export_jsonl import from_jsonl, to_jsonl
from groupwise.storage.export_parquet import from_parquet, to_parquet
from groupwise.storage.judging import JudgementInput, add_judgement, undo_judgement
from groupwise.storage.phases import FINISHED
from groupwise.storage.sessions import get_session
from groupwise.storage.timer import show_round


def _session_with_history(db, open_session) -> str:
    sid = open_session()
    with db.write() as s:
        show_round(s, sid, 0)
    with db.write() as s:
        add_judgement(
            s, sid, JudgementInput("a", 0, ("b1", "b2"), ("b3",), "left", "explored", 4.5, 2)
        )
        add_judgement(s, sid, JudgementInput("b", 0, ("b4",), ("b5",), "equal", "suggested"))
        undone, _ = add_judgement(
            s, sid, JudgementInput("c", 0, ("b6",), ("b7",), "right", "pairwise")
        )
        undo_judgement(s, sid, undone.id)
    return sid


def _comparable(export) -> tuple:
    """What must survive a round trip: everything but the session's own id and time."""
    judgements = [j.model_dump(exclude={"id"}) for j in export.judgements]
    session = export.session.model_dump(exclude={"id", "created_at", "phase"})
    return session, [r.model_dump() for r in export.rounds], judgements


@pytest.mark.parametrize(("write", "read"), [(to_jsonl, from_jsonl), (to_parquet, from_parquet)])
def test_export_import_round_trip(db, open_session, write, read):
    sid = _session_with_history(db, open_session)
    with db.read() as s:
        original = export_session(s, sid)
    assert len(original.judgements) == 3 and original.judgements[2].undone
    assert original.rounds[0].shown_at is not None
    data = write(original)
    with db.write() as s:
        imported = import_session(s, read(data))
        new_id = imported.id
    assert new_id != sid
    with db.read() as s:
        again = export_session(s, new_id)
        session = get_session(s, new_id)
        counted = counts(s, session)
    assert session.phase == FINISHED and session.origin == sid
    assert _comparable(again) == _comparable(original)
    assert (counted.comparisons_total, counted.pairs_total) == (2, 3)


def test_jsonl_is_one_object_per_line(db, open_session):
    sid = _session_with_history(db, open_session)
    with db.read() as s:
        lines = to_jsonl(export_session(s, sid)).decode().splitlines()
    kinds = [json.loads(line)["type"] for line in lines]
    assert kinds == ["session", "round", "annotator", "judgement", "judgement", "judgement"]
    assert "true_return" not in "".join(lines)  # never leaves the server


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"not json\n", "line 1 of the export is not JSON"),
        (b'{"type": "round", "round": 0}\n', "no session line"),
        (b'{"type": "what"}\n', "no known type"),
        (b'{"type": "session", "id": "s", "env": "GridWorld", "mode": "solo"}\n', "line 1: mode"),
        (b'{"type": "round", "round": 0, "close_reason": "a\\u0000"}\n', "line 1: close_reason"),
    ],
)
def test_bad_jsonl_is_rejected_with_its_line(data, message):
    with pytest.raises(InvalidError, match=message):
        from_jsonl(data)


def test_bad_parquet_is_rejected():
    with pytest.raises(InvalidError, match="not a Parquet file"):
        from_parquet(b"PAR1 but not really")


def test_a_judgement_of_an_unlisted_round_is_rejected(db, open_session):
    sid = _session_with_history(db, open_session)
    with db.read() as s:
        lines = to_jsonl(export_session(s, sid)).splitlines()
    without_rounds = b"\n".join(line for line in lines if b'"type":"round"' not in line)
    with pytest.raises(InvalidError, match="does not list"), db.write() as s:
        import_session(s, from_jsonl(without_rounds))
