"""Storing, retrying and undoing judgements (`storage.judging`) on real SQLite and
PostgreSQL databases."""

from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import func, select

from groupwise.storage import ConflictError, Database, InvalidError
from groupwise.storage.counts import counts
from groupwise.storage.judgements import list_judgements, round_judgements
from groupwise.storage.judging import JudgementInput, add_judgement, undo_judgement
from groupwise.storage.lifecycle import close_open_round
from groupwise.storage.models import JudgementRow, PairRow
from groupwise.storage.phases import ROUND_CLOSED, TRAINING
from groupwise.storage.sessions import get_round, get_session
from groupwise.storage.timer import show_round


def judgement(client_id: str = "c1", left=("b1", "b7"), right=("b3",), **kw) -> JudgementInput:
    fields = {"round": 0, "label": "left", "source": "explored", **kw}
    return JudgementInput(client_id, left=tuple(left), right=tuple(right), **fields)


def rows(db: Database, table) -> int:
    with db.read() as s:
        return int(s.scalar(select(func.count()).select_from(table)))


def test_a_judgement_is_stored_with_covering_pairs(db, open_session):
    sid = open_session()
    with db.write() as s:
        record, created = add_judgement(s, sid, judgement(left=("b1", "b7", "b8"), right=("b3",)))
    assert created
    # max(m, n) = 3 pairs, every member of both groups appears, left preferred
    assert len(record.pairs) == 3
    assert {p.a for p in record.pairs} == {"b1", "b7", "b8"}
    assert {p.b for p in record.pairs} == {"b3"}
    assert {p.label for p in record.pairs} == {1.0}
    with db.read() as s:
        stored = list_judgements(s, sid)
    assert [j.client_id for j in stored] == ["c1"]
    assert stored[0].pairs == record.pairs


def test_a_retry_with_the_same_client_id_stores_once(db, open_session):
    sid = open_session()
    with db.write() as s:
        first, created = add_judgement(s, sid, judgement())
    with db.write() as s:
        again, created_again = add_judgement(s, sid, judgement())
    assert created and not created_again
    assert again == first
    assert rows(db, JudgementRow) == 1
    assert rows(db, PairRow) == len(first.pairs) == 2


def test_a_client_id_reused_for_another_comparison_is_a_conflict(db, open_session):
    sid = open_session()
    with db.write() as s:
        add_judgement(s, sid, judgement())
    with pytest.raises(ConflictError, match="already used"), db.write() as s:
        add_judgement(s, sid, judgement(label="right"))


def test_undo_removes_the_pairs_and_keeps_the_record(db, open_session):
    sid = open_session()
    with db.write() as s:
        kept, _ = add_judgement(s, sid, judgement("keep", left=("b2",), right=("b4",)))
        gone, _ = add_judgement(s, sid, judgement("undo"))
    with db.write() as s:
        undone = undo_judgement(s, sid, gone.id)
    assert undone.undone and undone.pairs == ()
    assert rows(db, JudgementRow) == 2
    assert rows(db, PairRow) == len(kept.pairs) == 1
    with db.read() as s:
        assert [j.client_id for j in list_judgements(s, sid)] == ["keep"]
        assert [j.client_id for j in list_judgements(s, sid, include_undone=True)] == [
            "keep",
            "undo",
        ]
        assert [p.a for j in list_judgements(s, sid) for p in j.pairs] == ["b2"]
        assert [key for key, _ in round_judgements(s, sid, 0)] == [0]  # "undo" was key 1
        counted = counts(s, get_session(s, sid))
    assert (counted.comparisons_round, counted.pairs_round) == (1, 1)
    with db.write() as s:  # undoing twice changes nothing
        assert undo_judgement(s, sid, gone.id) == undone


@pytest.mark.parametrize(
    ("left", "right", "message"),
    [
        (("b1", "b3"), ("b3",), "b3 cannot be in both groups"),
        (("b1", "b1"), ("b3",), "twice"),
        (("b1",), ("b99",), "^b99 is not a behaviour of round 0$"),
        (("b98",), ("b99",), "^b98, b99 are not behaviours of round 0$"),
        (tuple(f"b{i}" for i in range(9)), ("b10",), "at most 8"),
        ((), ("b3",), "left group is empty"),
    ],
)
def test_bad_groups_are_rejected(db, open_session, left, right, message):
    sid = open_session()
    with pytest.raises(InvalidError, match=message), db.write() as s:
        add_judgement(s, sid, judgement(left=left, right=right))
    assert rows(db, JudgementRow) == 0


def test_pairwise_mode_takes_single_behaviours_only(db, open_session):
    sid = open_session(mode="pairwise")
    with pytest.raises(InvalidError, match="at most 1"), db.write() as s:
        add_judgement(s, sid, judgement(left=("b1", "b2"), right=("b3",)))


def test_pairs_are_reproducible_from_seed_round_and_sequence(db, open_session):
    groups = {"left": ("b0", "b1", "b2", "b5"), "right": ("b8", "b9")}
    sid_a, sid_b, sid_c = open_session(seed=3), open_session(seed=3), open_session(seed=4)
    pairs = {}
    for sid in (sid_a, sid_b, sid_c):
        with db.write() as s:
            pairs[sid] = add_judgement(s, sid, judgement(**groups))[0].pairs
    assert pairs[sid_a] == pairs[sid_b]
    assert len({pairs[sid_a], pairs[sid_c]}) == 2  # another seed shuffles differently


def test_judgements_only_for_the_open_round(db, open_session):
    sid = open_session()
    with pytest.raises(ConflictError, match="round 1 is not open yet; the open round is 0"):
        with db.write() as s:
            add_judgement(s, sid, judgement(round=1))
    with db.write() as s:
        record, _ = add_judgement(s, sid, judgement())
        close_open_round(s, sid)
    with pytest.raises(ConflictError, match="training"), db.write() as s:
        add_judgement(s, sid, judgement("late"))
    with pytest.raises(ConflictError, match="closed"), db.write() as s:
        undo_judgement(s, sid, record.id)
    with db.write() as s:  # a retry is still answered after the round closed
        assert add_judgement(s, sid, judgement())[0] == record


def test_the_comparison_budget_closes_the_round(db, open_session):
    sid = open_session(comparisons_per_round=2)
    with db.write() as s:
        add_judgement(s, sid, judgement("1"))
    with db.write() as s:
        add_judgement(s, sid, judgement("2", left=("b2",), right=("b4",)))
    with db.read() as s:
        session = get_session(s, sid)
        closed = get_round(s, sid, 0)
    assert session.phase == TRAINING
    assert (closed.phase, closed.close_reason) == (ROUND_CLOSED, "comparisons")
    assert closed.closed_at is not None and closed.closed_at.tzinfo == UTC
    assert closed.closed_at <= datetime.now(UTC)


def test_no_judgements_once_the_time_is_up(db, open_session):
    sid = open_session(round_seconds=60)
    with db.write() as s:
        started = show_round(s, sid, 0).shown_at
    assert started is not None
    with db.write() as s:
        add_judgement(s, sid, judgement("in time"), now=started + timedelta(seconds=59))
    with pytest.raises(ConflictError, match="time of round 0 is up"), db.write() as s:
        add_judgement(s, sid, judgement("late"), now=started + timedelta(seconds=61))


@pytest.mark.parametrize("field", ["client_id", "annotator"])
def test_a_nul_character_is_refused_on_every_backend(db, open_session, field):
    # PostgreSQL's text cannot hold one (it failed there with a 500); SQLite refuses it alike
    sid = open_session()
    fields = {"client_id": "c1", "annotator": "", field: "a\x00b"}
    bad = JudgementInput(fields["client_id"], 0, ("b1",), ("b2",), "left", "explored",
                         annotator=fields["annotator"])  # fmt: skip
    with pytest.raises(InvalidError, match=f"{field} contains a NUL character"), db.write() as s:
        add_judgement(s, sid, bad)
    assert rows(db, JudgementRow) == 0
