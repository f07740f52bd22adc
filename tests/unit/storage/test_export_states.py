"""Exports with states on SQLite and PostgreSQL: a hand-made pool of 12 behaviours of 4
steps (obs 2-d, acts 1-d) whose every number says where it came from."""

from pathlib import Path

import numpy as np
import pytest
from tests.unit.storage.conftest import N

from groupwise.cli import main as cli
from groupwise.storage import Database, InvalidError, NotFoundError, default_url
from groupwise.storage.export import StatesExport, export_session, import_session
from groupwise.storage.export_jsonl import from_jsonl, to_jsonl
from groupwise.storage.export_parquet import from_parquet, to_parquet
from groupwise.storage.judging import JudgementInput, add_judgement, undo_judgement
from groupwise.storage.sessions import get_round, list_sessions, round_directory
from groupwise.storage.states import preference_dataset

L = 4


def pool_arrays() -> dict[str, np.ndarray]:
    """behaviour i, step t: obs (i + t/10, -i), act i/100 + t, true reward i·t."""
    i, t = np.meshgrid(np.arange(N), np.arange(L), indexing="ij")
    return {
        "obs": np.stack([i + t / 10, -i + 0 * t], axis=-1).astype(np.float32),
        "acts": (i / 100 + t)[..., None].astype(np.float32),
        "true_rewards": (i * t).astype(np.float64),
    }


def write_pool(sid: str, data: Path) -> Path:
    """`pool_arrays` written as session `sid`'s round-0 pool, where the round row says, in
    the data dir `data`; returns `data`."""
    pool = data / round_directory(sid, 0)
    pool.mkdir(parents=True)
    np.savez(pool / "behaviours.npz", **pool_arrays())
    return data


@pytest.fixture
def judged(db, open_session, tmp_path) -> tuple[str, Path]:
    """A session with three judgements (one undone) over b1, b2, b3 v b4, b5 v b6 and b7 v
    b8; its round-0 pool written where the round row says. (session id, data dir)"""
    sid = open_session()
    data = write_pool(sid, tmp_path / "data")
    with db.write() as s:
        add_judgement(s, sid, JudgementInput("a", 0, ("b1", "b2"), ("b3",), "left", "explored"))
        add_judgement(s, sid, JudgementInput("b", 0, ("b5",), ("b4",), "right", "suggested"))
        undone, _ = add_judgement(
            s, sid, JudgementInput("c", 0, ("b7",), ("b8",), "equal", "pairwise")
        )
        undo_judgement(s, sid, undone.id)
    return sid, data


def test_an_export_with_states_holds_every_compared_behaviour(db, judged):
    sid, data = judged
    with db.read() as s:
        export = export_session(s, sid, StatesExport(data))
    (states,) = export.behaviours
    assert states.names == ("b1", "b2", "b3", "b4", "b5", "b7", "b8")  # the undone too
    expected = pool_arrays()
    rows = [1, 2, 3, 4, 5, 7, 8]
    np.testing.assert_array_equal(states.obs, expected["obs"][rows])
    np.testing.assert_array_equal(states.acts, expected["acts"][rows])
    np.testing.assert_array_equal(states.true_rewards, expected["true_rewards"][rows])
    assert states.obs[1, 3].tolist() == pytest.approx([2.3, -2.0])  # b2 at step 3
    with db.read() as s:
        hidden = export_session(s, sid, StatesExport(data, true_rewards=False))
    assert hidden.behaviours[0].true_rewards is None


@pytest.mark.parametrize(("write", "read"), [(to_jsonl, from_jsonl), (to_parquet, from_parquet)])
def test_states_survive_export_and_import_into_another_data_directory(
    db, judged, tmp_path, write, read
):
    sid, data = judged
    with db.read() as s:
        original = export_session(s, sid, StatesExport(data))
        trained_before = preference_dataset(s, data, sid)
    parsed = read(write(original))
    other = tmp_path / "other"
    with db.write() as s:
        new_id = import_session(s, parsed, data_dir=other).id
    with db.read() as s:
        again = export_session(s, new_id, StatesExport(other))
        trained_after = preference_dataset(s, other, new_id)
    (before,), (after,) = original.behaviours, again.behaviours
    assert after.names == before.names
    for field in ("obs", "acts", "true_rewards"):
        np.testing.assert_array_equal(getattr(after, field), getattr(before, field))
        assert getattr(after, field).dtype == getattr(before, field).dtype
    # the pairs of the two live judgements: b1>b3, b2>b3 (cover) and b4>b5
    assert len(trained_after) == 3 and trained_after.n_fragments == 5
    np.testing.assert_array_equal(trained_after.obs, trained_before.obs)
    np.testing.assert_array_equal(trained_after.pairs, trained_before.pairs)
    np.testing.assert_array_equal(trained_after.labels, trained_before.labels)
    # true return of b<i>: i · (0 + 1 + 2 + 3)
    np.testing.assert_array_equal(trained_after.true_returns, 6.0 * np.arange(1, 6))


def test_an_import_with_states_needs_every_compared_behaviour(db, judged, tmp_path):
    sid, data = judged
    with db.read() as s:
        lines = to_jsonl(export_session(s, sid, StatesExport(data))).splitlines()
    without_b3 = b"\n".join(line for line in lines if b'"id":"b3"' not in line)
    with pytest.raises(InvalidError, match="lack b3"), db.write() as s:
        import_session(s, from_jsonl(without_b3), data_dir=tmp_path / "other")
    with pytest.raises(InvalidError, match="into a data directory"), db.write() as s:
        import_session(s, from_jsonl(b"\n".join(lines)))


def test_states_are_read_only_inside_the_data_directory(db, judged, tmp_path):
    sid, data = judged
    outside = tmp_path / "elsewhere"
    (outside / "pool").mkdir(parents=True)
    np.savez(outside / "pool" / "behaviours.npz", **pool_arrays())
    with db.write() as s:  # as an imported export could name it
        get_round(s, sid, 0).pool_dir = "../elsewhere/pool"
    with pytest.raises(NotFoundError, match="not in the data directory"), db.read() as s:
        export_session(s, sid, StatesExport(data))
    with db.read() as s:  # without states the export does not look
        assert len(export_session(s, sid).judgements) == 3


def docs_example(name: str, marker: str) -> str:
    """The first ```python block of docs/`name` that contains `marker`."""
    text = (Path(__file__).parents[3] / "docs" / name).read_text()
    blocks = [b.split("```", 1)[0] for b in text.split("```python\n")[1:]]
    return next(b for b in blocks if marker in b)


def test_groupwise_import_counts_what_it_stores_and_the_docs_example_reads_it(
    db, judged, tmp_path, capsys
):
    sid, data = judged
    with db.read() as s:
        exported = tmp_path / "feedback.jsonl"
        exported.write_bytes(to_jsonl(export_session(s, sid, StatesExport(data))))
    fresh = tmp_path / "fresh"
    assert cli(["import", str(exported), "--data", str(fresh)]) == 0
    # three stored, one of them undone; the two live ones give three pairs
    assert "(3 judgements (1 undone), 3 pairs, with states)" in capsys.readouterr().out
    fresh_db = Database(default_url(fresh))
    with fresh_db.read() as s:
        (imported,) = list_sessions(s)
    fresh_db.dispose()
    # docs/export.md's example as written, DIR a str (issue 40: TypeError before)
    scope = {"DIR": str(fresh), "session_id": imported.id}
    exec(docs_example("export.md", "default_url(DIR)"), scope)
    assert len(scope["dataset"]) == 3 and scope["dataset"].n_fragments == 5
    assert default_url(str(fresh)) == default_url(fresh) == f"sqlite:///{fresh}/groupwise.db"
