"""`groupwise export --format ipl-npz | pt-indices`: a session's pairs read back as IPL/CPL
and Preference Transformer/Uni-RLHF read them equal the pairs the reward model trains on
(issue 42). The pool is the hand-made one of test_export_states: 12 behaviours of 4 steps."""

import os
import pickle
from pathlib import Path

import numpy as np
import pytest
from tests.unit.storage.test_export_states import L, docs_example, pool_arrays, write_pool

from groupwise.cli import main as cli
from groupwise.storage import InvalidError
from groupwise.storage.export import StatesExport, export_session
from groupwise.storage.export_offline import env_slug, index_codes, offline_pairs
from groupwise.storage.judging import JudgementInput, add_judgement, undo_judgement
from groupwise.storage.states import preference_dataset


@pytest.fixture
def judged(db, open_session, tmp_path) -> tuple[str, Path]:
    """b1, b2 ≻ b3; b4 ≻ b5 (said as "right" of b5 v b4); b7 = b8; b9 ≻ b10 undone."""
    sid = open_session()
    data = write_pool(sid, tmp_path / "data")
    with db.write() as s:
        add_judgement(s, sid, JudgementInput("a", 0, ("b1", "b2"), ("b3",), "left", "explored"))
        add_judgement(s, sid, JudgementInput("b", 0, ("b5",), ("b4",), "right", "suggested"))
        add_judgement(s, sid, JudgementInput("c", 0, ("b7",), ("b8",), "equal", "pairwise"))
        undone, _ = add_judgement(
            s, sid, JudgementInput("d", 0, ("b9",), ("b10",), "left", "pairwise")
        )
        undo_judgement(s, sid, undone.id)
    return sid, data


def _export(database_url: str, sid: str, data: Path, fmt: str, out: Path, *more: str) -> int:
    args = ["export", sid, "--data", str(data), "--db", database_url, "--format", fmt]
    return cli([*args, "-o", str(out), *more])


def _session_pairs(db, sid: str, data: Path):
    """What the reward model trains on: each pair's two behaviours' arrays and P(a ≻ b)."""
    with db.read() as s:
        ds = preference_dataset(s, data, sid)
    a, b = ds.pairs[:, 0], ds.pairs[:, 1]
    true = pool_arrays()["true_rewards"]
    return ds, a, b, true


def test_ipl_npz_round_trips_into_the_sessions_pairs(db, database_url, judged, tmp_path):
    sid, data = judged
    out = tmp_path / "prefs.npz"
    assert _export(database_url, sid, data, "ipl-npz", out) == 0
    ds, a, b, _ = _session_pairs(db, sid, data)
    with np.load(out) as npz:
        loaded = dict(npz)
    assert set(loaded) == {"obs_1", "obs_2", "action_1", "action_2", "label", "reward_1",
                           "reward_2"}  # fmt: skip
    assert loaded["obs_1"].shape == (4, L, 2) and loaded["label"].shape == (4,)
    np.testing.assert_array_equal(loaded["obs_1"], ds.obs[a])
    np.testing.assert_array_equal(loaded["obs_2"], ds.obs[b])
    np.testing.assert_array_equal(loaded["action_1"], ds.acts[a])
    np.testing.assert_array_equal(loaded["action_2"], ds.acts[b])
    np.testing.assert_array_equal(loaded["label"], 1.0 - ds.labels)
    # hand-checked: (b1, b3) and (b2, b3) first preferred, (b5, b4) second, (b7, b8) equal
    assert loaded["label"].tolist() == [0.0, 0.0, 1.0, 0.5]
    assert sorted(loaded["obs_1"][:2, 0, 0]) == [1.0, 2.0] and loaded["obs_2"][0, 0, 0] == 3.0
    assert loaded["obs_1"][2:, 0, 0].tolist() == [5.0, 7.0]
    assert loaded["reward_2"][2].tolist() == [0.0, 4.0, 8.0, 12.0]  # b4: reward i·t


def test_ipl_npz_loads_as_cpl_reads_it(database_url, judged, tmp_path):
    sid, data = judged
    path = tmp_path / "prefs.npz"
    assert _export(database_url, sid, data, "ipl-npz", path) == 0
    namespace: dict = {"path": str(path)}
    exec(docs_example("export.md", "CPL's FeedbackBuffer"), namespace)
    score = namespace["data"]["label"]
    assert score.tolist() == [1.0, 1.0, 0.0, 0.5, 0.0, 0.0, 1.0, 0.5]  # segment 1's, then 2's
    assert namespace["data"]["obs"].shape == (8, L, 2)


def test_pt_indices_round_trip_into_the_sessions_pairs(db, database_url, judged, tmp_path):
    sid, data = judged
    out = tmp_path / "pt"
    assert _export(database_url, sid, data, "pt-indices", out) == 0
    ds, a, b, _ = _session_pairs(db, sid, data)
    env = env_slug("GridWorld")
    base = out / "human_label" / env
    assert sorted(os.listdir(base)) == ["indices_2_num4", "indices_num4", "label_human"]
    with (base / "indices_num4").open("rb") as f:
        starts_1 = pickle.load(f)
    with (base / "indices_2_num4").open("rb") as f:
        starts_2 = pickle.load(f)
    with (base / "label_human").open("rb") as f:
        labels = pickle.load(f)
    dataset = dict(np.load(out / "dataset.npz"))
    for starts, rows in ((starts_1, a), (starts_2, b)):
        obs = np.stack([dataset["observations"][s : s + L] for s in starts])
        acts = np.stack([dataset["actions"][s : s + L] for s in starts])
        np.testing.assert_array_equal(obs, ds.obs[rows])
        np.testing.assert_array_equal(acts, ds.acts[rows])
    assert np.asarray(labels).tolist() == [0, 0, 1, -1]
    assert len(dataset["observations"]) == 7 * L  # b1, b2, b3, b4, b5, b7, b8 once each
    assert dataset["timeouts"].nonzero()[0].tolist() == [L * k - 1 for k in range(1, 8)]
    # Uni-RLHF's names, in the order its loader unpacks sorted(os.listdir(...))
    uni = sorted(os.listdir(out / f"{env}_human_labels"))
    suffix = f"_domain_groupwise_env_{env}_num_4_len_{L}_{sid}.pkl"
    assert uni == [f"human_label{suffix}", f"indices_1{suffix}", f"indices_2{suffix}"]
    with (out / f"{env}_human_labels" / uni[1]).open("rb") as f:
        np.testing.assert_array_equal(pickle.load(f), starts_1)


def test_pt_indices_load_as_uni_rlhf_reads_them(database_url, judged, tmp_path):
    sid, data = judged
    out = tmp_path / "pt"
    assert _export(database_url, sid, data, "pt-indices", out) == 0
    namespace: dict = {"export_dir": str(out), "env": "GridWorld", "num_query": 4, "len_query": L}
    exec(docs_example("export.md", "Uni-RLHF's train_reward_model.py"), namespace)
    batch = namespace["batch"]
    assert batch["labels"].tolist() == [[1, 0], [1, 0], [0, 1], [0.5, 0.5]]
    assert batch["observations"].shape == (4, L, 2)
    assert batch["observations_2"][2, 0].tolist() == [4.0, -4.0]  # b4 at step 0


def test_without_true_rewards_and_without_pairs(db, database_url, judged, open_session, tmp_path):
    sid, data = judged
    out = tmp_path / "prefs.npz"
    assert _export(database_url, sid, data, "ipl-npz", out, "--no-true-rewards") == 0
    with np.load(out) as npz:
        assert "reward_1" not in npz and len(npz["label"]) == 4
    assert _export(database_url, sid, data, "pt-indices", tmp_path / "pt", "--no-true-rewards") == 0
    assert np.isnan(np.load(tmp_path / "pt" / "dataset.npz")["rewards"]).all()
    empty = open_session()
    with db.read() as s:
        export = export_session(s, empty, StatesExport(data))
    with pytest.raises(InvalidError, match="has no preference pairs"):
        offline_pairs(export)


def test_labels_without_an_index_code_are_refused() -> None:
    assert index_codes(np.array([1.0, 0.0, 0.5])).tolist() == [0, 1, -1]
    with pytest.raises(InvalidError, match=r"pair 1 has label 0\.25"):
        index_codes(np.array([1.0, 0.25]))
