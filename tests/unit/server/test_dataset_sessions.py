"""A labelling session over a recorded dataset through the HTTP API (issue 42, deliverable
2): a Minari dataset built here with Minari's own DataCollector, the worker run in process;
the session has no agent, fits its reward ensemble from the labels and ends without PPO."""

import json
import uuid

import numpy as np
import pytest
from tests.datasets import HOPPER, build_hopper_dataset
from tests.unit.server.conftest import context_of, run_worker_once

from groupwise.cli import main
from groupwise.commands.serve import choose_session
from groupwise.reward import RewardEnsemble
from groupwise.run.checkpoint import REWARD_FILE, STATE_FILE, checkpoint_dir
from groupwise.storage import sqlite_url

pytest.importorskip("minari")
pytest.importorskip("jax")  # Minari's DataCollector needs it (groupwise[dev])

DATASET = "test/hopper-random-v0"
SMALL = {
    "pool_size": 8,
    "fragment_length": 10,
    "comparisons_per_round": 0,
    "rounds": 1,
    "frame_size": 32,
    "render_workers": 0,
    "ppo_steps_per_round": 20_000,  # set to 0: a dataset session trains no agent
    "research": {"reward": {"ensemble_size": 2}},
}


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    root = tmp_path_factory.mktemp("minari")
    build_hopper_dataset(root, DATASET, steps=400)
    return root


@pytest.fixture
def minari_store(store, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(store))
    return store


def leaves_of(node):
    if node["kind"] == "leaf":
        return [node]
    return [leaf for child in node["children"] for leaf in leaves_of(child)]


def create(client, **body):
    return client.post("/api/sessions", json={"mode": "groupwise", **body})


def test_a_dataset_session_ends_with_its_pairs_and_a_fitted_ensemble(client, minari_store):
    response = create(client, settings={**SMALL, "dataset": f"minari:{DATASET}"})
    assert response.status_code == 201, response.text
    session = response.json()
    sid = session["id"]
    assert session["env"] == HOPPER  # the dataset's own env
    settings = session["settings"]
    assert settings["dataset"] == f"minari:{DATASET}"
    assert (settings["training"], settings["ppo_steps_per_round"], settings["final_steps"]) == (
        "rounds",
        0,
        0,
    )

    run_worker_once(client)  # prepare round 0: windows of the dataset
    tree = client.get(f"/api/sessions/{sid}/rounds/0/tree").json()
    found = leaves_of(tree["tree"])
    leaves = sorted(leaf["id"] for leaf in found)
    assert leaves == sorted(f"b{i}" for i in range(8))
    clip = client.get(f"/clips/{found[0]['clip']}")
    assert clip.status_code == 200 and clip.headers["content-type"] == "video/mp4"

    body = {
        "client_id": str(uuid.uuid4()),
        "round": 0,
        "left": leaves[:2],
        "right": leaves[2:5],
        "label": "left",
        "source": "explored",
    }
    judged = client.post(f"/api/sessions/{sid}/judgements", json=body)
    assert judged.status_code == 201, judged.text
    assert len(judged.json()["pairs"]) == 3  # max(m, n) = max(2, 3)
    assert client.post(f"/api/sessions/{sid}/end-round").status_code == 200
    run_worker_once(client)  # train round 0: the reward fit, no PPO, no evaluation
    assert client.get(f"/api/sessions/{sid}").json()["phase"] == "finishing"
    run_worker_once(client)  # the final phase: nothing to train, no agent to hand over
    done = client.get(f"/api/sessions/{sid}").json()
    assert (done["phase"], done["error"]) == ("finished", None)

    directory = context_of(client).data_dir / "sessions" / sid
    assert not (directory / "agent.zip").exists()
    assert client.get(f"/api/sessions/{sid}/agent").status_code == 404  # none to hand over
    checkpoint = checkpoint_dir(directory, 0)
    state = json.loads((checkpoint / STATE_FILE).read_text())
    assert state["records"][-1]["env_steps"] == 0  # PPO never ran
    assert state["records"][-1]["pairs_total"] == 3
    assert np.isfinite(state["records"][-1]["reward_loss"])  # the ensemble was fitted
    ensemble = RewardEnsemble.load(checkpoint / REWARD_FILE)
    windows = np.random.default_rng(0).normal(size=(4, 10, 11)).astype(np.float32)
    returns = ensemble.returns(windows, np.zeros((4, 10, 3), np.float32))
    assert returns.shape == (4, 2) and np.ptp(returns) > 0
    lines = client.get(f"/api/sessions/{sid}/export").text.splitlines()
    exported = [json.loads(line) for line in lines]
    judgements = [row for row in exported if row["type"] == "judgement"]
    assert [len(row["pairs"]) for row in judgements] == [3]


def test_a_dataset_session_is_refused_in_one_line(client, minari_store, tmp_path):
    missing = create(client, settings={**SMALL, "dataset": "minari:mujoco/hopper/expert-v0"})
    assert missing.status_code == 422
    assert "never downloads" in missing.json()["detail"]
    wrong_env = create(client, env="GridWorld", settings={**SMALL, "dataset": f"minari:{DATASET}"})
    assert wrong_env.status_code == 422 and "env GridWorld has" in wrong_env.json()["detail"]
    too_long = create(
        client, settings={**SMALL, "fragment_length": 1000, "dataset": f"minari:{DATASET}"}
    )
    assert too_long.status_code == 422 and "windows of 1000 steps" in too_long.json()["detail"]
    for path in (str(tmp_path / "nothing.hdf5"), "/" + "a" * 600, str(tmp_path)):
        refused = create(client, settings={**SMALL, "dataset": path})
        assert refused.status_code == 422 and "dataset" in refused.json()["detail"], path
    no_env = create(client, settings=SMALL)
    assert no_env.status_code == 422 and "env is required" in no_env.json()["detail"]


def test_serve_dataset_opens_a_session_of_the_datasets_env_and_resumes_only_it(
    tmp_path, minari_store, capsys
):
    url = sqlite_url(tmp_path / "groupwise.db")
    plain = choose_session(url, HOPPER, "groupwise", {"fragment_length": 10}, None, True)
    asked = {"fragment_length": 10, "dataset": f"minari:{DATASET}"}
    first = choose_session(url, None, "groupwise", asked, None, False)
    assert (first.env, first.verb) == (HOPPER, "new") and first.session_id != plain.session_id
    again = choose_session(url, None, "groupwise", asked, None, False)
    assert (again.session_id, again.verb) == (first.session_id, "resuming")
    directory = str(minari_store / DATASET)
    by_path = choose_session(url, None, "groupwise", {**asked, "dataset": directory}, None, False)
    assert by_path.verb == "new"  # another reference: another session

    code = main(["serve", "--data", str(tmp_path / "d"), "--dataset", "minari:nope/none-v0"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "never downloads" in err
    assert not (tmp_path / "d" / "groupwise.db").exists()
