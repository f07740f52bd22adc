"""Feedback others can reuse (issue 21): an export with states carries each compared
behaviour's arrays, pandas and Hugging Face `datasets` read its Parquet as it is, and an
import into a fresh data directory, without the pools, trains a reward model.

On a real GridWorld round (the worker's pool in the data directory), SQLite and PostgreSQL.
"""

import io
import json

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from sqlalchemy import select
from tests.unit.server.conftest import context_of

from groupwise.cli import main as cli
from groupwise.config import RewardConfig
from groupwise.pool.files import load_pool
from groupwise.reward.bradley_terry import fit
from groupwise.reward.ensemble import RewardEnsemble
from groupwise.storage import Database, default_url
from groupwise.storage.export_jsonl import from_jsonl
from groupwise.storage.models import SessionRow
from groupwise.storage.sessions import round_directory
from groupwise.storage.states import preference_dataset


@pytest.fixture(scope="module")
def judged(prepared):
    """The groupwise session of `prepared` with 24 answers, each 1 v 1 or a group, labelled
    by the behaviours' true returns (a consistent teacher); (client, session id, pool)."""
    client, sid, _ = prepared
    context = context_of(client)
    pool = load_pool(context.data_dir / round_directory(sid, 0), 0)
    returns = np.array([f.true_return for f in pool.fragments])
    rng = np.random.default_rng(21)
    for k in range(24):
        m, n = (1, 1) if k % 2 == 0 else (2, 1)
        picked = rng.choice(len(returns), size=m + n, replace=False)
        left, right = picked[:m], picked[m:]
        gap = returns[left].mean() - returns[right].mean()
        body = {
            "client_id": f"teacher-{k}",
            "round": 0,
            "left": [f"b{i}" for i in left],
            "right": [f"b{i}" for i in right],
            "label": "left" if gap > 0 else "right" if gap < 0 else "equal",
            "source": "explored",
        }
        response = client.post(f"/api/sessions/{sid}/judgements", json=body)
        assert response.status_code == 201, response.text
    return client, sid, pool


def test_the_default_export_holds_ids_alone(judged):
    client, sid, _ = judged
    body = client.get(f"/api/sessions/{sid}/export?format=parquet").content
    columns = pq.read_table(io.BytesIO(body)).column_names
    assert not [c for c in columns if c.endswith(("_obs", "_acts", "_true_rewards"))]


def test_a_parquet_export_with_states_reads_as_it_is_and_equals_the_pool(judged):
    client, sid, pool = judged
    body = client.get(f"/api/sessions/{sid}/export?format=parquet&states=1").content
    frame = pd.read_parquet(io.BytesIO(body))
    assert len(frame) == 24
    # the session is still open: no true rewards leave the server
    assert "left_true_rewards" not in frame.columns
    for _, row in frame.iterrows():
        for side in ("left", "right"):
            obs, acts = _array(row[f"{side}_obs"]), _array(row[f"{side}_acts"])
            assert obs.dtype == acts.dtype == np.float32
            assert obs.shape[0] == acts.shape[0] == len(row[side])
            for k, name in enumerate(row[side]):
                fragment = pool.fragments[int(name[1:])]
                np.testing.assert_array_equal(obs[k], fragment.obs)
                np.testing.assert_array_equal(acts[k], fragment.acts)


def _array(value) -> np.ndarray:
    """pandas' nested lists (object arrays of arrays) as one array."""
    if isinstance(value, np.ndarray) and value.dtype == object:
        return np.stack([_array(v) for v in value])
    return np.asarray(value)


def test_hugging_face_datasets_loads_the_parquet(judged, tmp_path, monkeypatch):
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    monkeypatch.setenv("HF_DATASETS_OFFLINE", "1")
    datasets = pytest.importorskip("datasets")  # the dev extra installs it
    client, sid, pool = judged
    path = tmp_path / "feedback.parquet"
    path.write_bytes(client.get(f"/api/sessions/{sid}/export?format=parquet&states=1").content)
    loaded = datasets.load_dataset(
        "parquet", data_files=str(path), split="train", cache_dir=str(tmp_path / "hf")
    )
    assert loaded.num_rows == 24
    first = loaded.with_format("numpy")[0]
    name = first["left"][0]
    np.testing.assert_array_equal(
        np.asarray(first["left_obs"][0], dtype=np.float32), pool.fragments[int(name[1:])].obs
    )


def test_a_jsonl_export_with_states_carries_each_behaviour_once(judged):
    client, sid, pool = judged
    body = client.get(f"/api/sessions/{sid}/export?format=jsonl&states=1").content
    kinds = [json.loads(line)["type"] for line in body.splitlines()]
    export = from_jsonl(body)
    (states,) = export.behaviours
    compared = {n for j in export.judgements for n in (*j.left, *j.right)}
    assert set(states.names) == compared and kinds.count("behaviour") == len(compared)
    for k, name in enumerate(states.names):
        np.testing.assert_array_equal(states.obs[k], pool.fragments[int(name[1:])].obs)
        np.testing.assert_array_equal(states.acts[k], pool.fragments[int(name[1:])].acts)
    assert states.true_rewards is None


def test_an_import_without_the_pools_trains_a_reward_model(judged, tmp_path, capsys):
    client, sid, pool = judged
    context = context_of(client)
    exported = tmp_path / "feedback.parquet"
    source = ["--data", str(context.data_dir), "--db", context.db.url]
    assert cli(["export", sid, *source, "--states", "-o", str(exported)]) == 0
    fresh = tmp_path / "fresh"  # another machine: no pools, a new SQLite database
    assert cli(["import", str(exported), "--data", str(fresh)]) == 0
    assert "24 judgements" in capsys.readouterr().out
    assert not list(fresh.glob("sessions/*/round-*/behaviours.npz"))

    with context.db.read() as s:
        original = preference_dataset(s, context.data_dir, sid)
    db = Database(default_url(fresh))
    try:
        with db.read() as s:
            (imported_id,) = [row.id for row in s.scalars(select(SessionRow))]
            dataset = preference_dataset(s, fresh, imported_id)
    finally:
        db.dispose()
    # the same pairs over the same arrays as the original session's (and the pool's)
    for field in ("obs", "acts", "pairs", "labels", "rounds"):
        np.testing.assert_array_equal(getattr(dataset, field), getattr(original, field))
    np.testing.assert_allclose(dataset.true_returns, original.true_returns)
    returns = {round(f.true_return, 9) for f in pool.fragments}
    assert {round(r, 9) for r in dataset.true_returns} <= returns

    cfg = RewardConfig()
    rng = np.random.default_rng(0)
    ensemble = RewardEnsemble(dataset.obs.shape[2], dataset.acts.shape[2], cfg, rng)
    report = fit(ensemble, dataset, cfg, rng, epochs=60)
    assert report.n_pairs == len(dataset) >= 24
    # a consistent teacher's pairs are learnable: the fitted returns rank most of them
    assert report.accuracy >= 0.8
