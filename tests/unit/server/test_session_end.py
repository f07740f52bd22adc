"""The end of a session in process: the final phase, the agent's summary, video and zip,
"Finish now" and "Continue training", and their refusals (docs/app.md, "Session end")."""

import csv
import io
import json
import uuid
import zipfile

import numpy as np
import pytest
from tests.unit.server.conftest import context_of, new_session, run_worker_once

import groupwise
from groupwise.clips.video import probe


def judge(client, sid, round_index=0):
    body = {
        "client_id": str(uuid.uuid4()),
        "round": round_index,
        "left": ["b1", "b2"],
        "right": ["b3"],
        "label": "left",
        "source": "explored",
    }
    response = client.post(f"/api/sessions/{sid}/judgements", json=body)
    assert response.status_code == 201, response.text


def state(client, sid):
    return client.get(f"/api/sessions/{sid}").json()


def rounds_csv(client, sid):
    path = context_of(client).data_dir / "sessions" / sid / "rounds.csv"
    return list(csv.DictReader(path.open()))


def finished_session(client, **settings):
    """A one-round session answered once, trained and finished (final phase included)."""
    sid = new_session(client, rounds=1, final_steps=64, **settings)["id"]
    run_worker_once(client)  # prepare round 0
    judge(client, sid)
    client.post(f"/api/sessions/{sid}/end-round")
    run_worker_once(client)  # train round 0
    after = state(client, sid)
    assert (after["phase"], after["round"]) == ("finishing", 1), after
    assert client.get(f"/api/sessions/{sid}/agent").status_code == 409
    run_worker_once(client)  # the final phase: round 1 without feedback
    return sid


def test_the_final_phase_trains_on_the_frozen_reward_and_publishes_the_agent(client, tmp_path):
    sid = finished_session(client)
    done = state(client, sid)
    assert (done["phase"], done["round"], done["error"]) == ("finished", 1, None)
    assert done["progress"]["phase"] == "finished"

    rows = rounds_csv(client, sid)
    assert [int(r["round"]) for r in rows] == [0, 1]
    final = rows[1]
    assert int(final["comparisons"]) == 0 and int(final["pairs"]) == 0
    assert final["reward_loss"] == "nan"  # no reward fit: the reward is frozen
    assert int(final["env_steps"]) >= int(rows[0]["env_steps"]) + 64
    directory = context_of(client).data_dir / "sessions" / sid
    config = json.loads((directory / "config.json").read_text())
    assert config["loop"]["decision_maker"] == "human" and config["loop"]["final_steps"] == 64

    agent = client.get(f"/api/sessions/{sid}/agent").json()
    assert agent["round"] == 1 and agent["measure"] == "true return"
    assert (agent["target"], agent["target_score_mean"]) == (None, None)  # not a target env
    assert [(r["round"], r["feedback"]) for r in agent["rounds"]] == [(0, True), (1, False)]
    assert agent["rounds"][0]["judgements"] == 1
    assert agent["video"]["frames"] >= 1 and agent["video"]["width"] == 32

    video = client.get(f"/api/sessions/{sid}/agent.mp4")
    assert video.status_code == 200 and video.headers["content-type"] == "video/mp4"
    (tmp_path / "agent.mp4").write_bytes(video.content)
    info = probe(tmp_path / "agent.mp4")
    assert (info.codec, info.pix_fmt, info.faststart) == ("h264", "yuv420p", True)

    download = client.get(f"/api/sessions/{sid}/agent.zip")
    assert download.status_code == 200
    assert f"groupwise-agent-{sid}-round-1.zip" in download.headers["content-disposition"]
    names = set(zipfile.ZipFile(io.BytesIO(download.content)).namelist())
    assert {"README.md", "agent.json", "policy.zip", "vecnormalize.npz", "reward.pt"} <= names
    assert {"config.json", "settings.json", "rounds.csv"} <= names
    (tmp_path / "agent.zip").write_bytes(download.content)
    loaded = groupwise.load_agent(tmp_path / "agent.zip")
    assert loaded.env == "GridWorld" and loaded.summary.round == 1
    assert loaded.config().loop.decision_maker == "human"
    assert loaded.reward_model().size >= 1


def test_a_session_without_final_steps_publishes_its_last_rounds_agent(client):
    sid = new_session(client, rounds=1, final_steps=0)["id"]
    run_worker_once(client)
    client.post(f"/api/sessions/{sid}/end-round")
    run_worker_once(client)
    assert (state(client, sid)["phase"], state(client, sid)["round"]) == ("finishing", 0)
    run_worker_once(client)
    assert state(client, sid)["phase"] == "finished"
    assert [int(r["round"]) for r in rounds_csv(client, sid)] == [0]
    agent = client.get(f"/api/sessions/{sid}/agent").json()
    assert agent["round"] == 0 and [r["feedback"] for r in agent["rounds"]] == [True]


def test_continue_training_with_more_steps_and_more_rounds(client):
    sid = finished_session(client)
    more = client.post(f"/api/sessions/{sid}/continue", json={"steps": 32}).json()
    assert (more["phase"], more["round"]) == ("finishing", 2)
    run_worker_once(client)
    agent = client.get(f"/api/sessions/{sid}/agent").json()
    assert agent["round"] == 2
    assert [r["feedback"] for r in agent["rounds"]] == [True, False, False]

    again = client.post(f"/api/sessions/{sid}/continue", json={"rounds": 1}).json()
    assert (again["phase"], again["round"], again["rounds"]) == ("preparing", 3, 4)
    run_worker_once(client)  # prepare round 3 from round 2's agent
    assert state(client, sid)["phase"] == "ready"
    judge(client, sid, round_index=3)
    client.post(f"/api/sessions/{sid}/end-round")
    run_worker_once(client)  # train round 3, then the final phase (round 4)
    assert (state(client, sid)["phase"], state(client, sid)["round"]) == ("finishing", 4)
    run_worker_once(client)
    agent = client.get(f"/api/sessions/{sid}/agent").json()
    assert [(r["round"], r["feedback"]) for r in agent["rounds"]] == [
        (0, True),
        (1, False),
        (2, False),
        (3, True),
        (4, False),
    ]
    assert [int(r["round"]) for r in rounds_csv(client, sid)] == [0, 1, 2, 3, 4]


def test_finish_now_ends_the_open_round_then_the_final_phase(client):
    sid = new_session(client, rounds=5, final_steps=32)["id"]
    assert client.post(f"/api/sessions/{sid}/finish").status_code == 409  # round 0 preparing
    run_worker_once(client)
    judge(client, sid)
    finishing = client.post(f"/api/sessions/{sid}/finish").json()
    assert (finishing["phase"], finishing["rounds"]) == ("training", 1)
    run_worker_once(client)
    assert state(client, sid)["phase"] == "finishing"
    assert client.post(f"/api/sessions/{sid}/finish").status_code == 409
    run_worker_once(client)
    assert (state(client, sid)["phase"], state(client, sid)["round"]) == ("finished", 1)


def test_finish_now_while_a_round_is_prepared_drops_that_round(client):
    sid = new_session(client, rounds=3, final_steps=32, training="rounds")["id"]
    run_worker_once(client)
    judge(client, sid)
    client.post(f"/api/sessions/{sid}/end-round")
    run_worker_once(client)
    assert (state(client, sid)["phase"], state(client, sid)["round"]) == ("preparing", 1)
    after = client.post(f"/api/sessions/{sid}/finish").json()
    # round 1 is never prepared: it becomes the final phase's round
    assert (after["phase"], after["round"], after["rounds"]) == ("finishing", 1, 1)
    run_worker_once(client)
    assert state(client, sid)["phase"] == "finished"
    assert client.get(f"/api/sessions/{sid}/agent").json()["rounds"][1]["feedback"] is False


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ({}, "give either steps or rounds"),
        ({"steps": 10, "rounds": 1}, "give either steps or rounds"),
        ({"steps": 0}, "steps"),
        ({"rounds": 1, "extra": 1}, "extra"),
    ],
)
def test_continue_validates_its_body(client, body, words):
    sid = new_session(client)["id"]
    response = client.post(f"/api/sessions/{sid}/continue", json=body)
    assert response.status_code == 422 and words in response.json()["detail"]


def test_the_end_of_a_session_refuses_clearly(client):
    for path in ("agent", "agent.mp4", "agent.zip"):
        missing = client.get(f"/api/sessions/s-000000000000/{path}")
        assert missing.status_code == 404
        assert "no session" in missing.json()["detail"]
    missing = client.post("/api/sessions/s-000000000000/continue", json={"steps": 5})
    assert missing.status_code == 404
    sid = new_session(client)["id"]
    early = client.get(f"/api/sessions/{sid}/agent.zip")
    assert early.status_code == 409 and "once it is finished" in early.json()["detail"]
    refused = client.post(f"/api/sessions/{sid}/continue", json={"steps": 5})
    assert refused.status_code == 409 and "once it is finished" in refused.json()["detail"]


def test_an_imported_session_has_no_agent_to_show_or_continue(client):
    sid = new_session(client)["id"]
    export = client.get(f"/api/sessions/{sid}/export").content
    imported = client.post(
        "/api/sessions/import", content=export, headers={"content-type": "application/x-ndjson"}
    ).json()
    assert imported["phase"] == "finished"
    assert client.get(f"/api/sessions/{imported['id']}/agent").status_code == 404
    refused = client.post(f"/api/sessions/{imported['id']}/continue", json={"rounds": 1})
    assert refused.status_code == 409 and "no trained agent" in refused.json()["detail"]


def test_load_agent_predicts_and_evaluates(client, tmp_path):
    sid = finished_session(client)
    path = context_of(client).data_dir / "sessions" / sid / "agent.zip"
    agent = groupwise.load_agent(path)
    env = agent.make_env()
    obs, _ = env.reset(seed=0)
    action = agent.predict(obs)
    assert env.action_space.contains(action.item() if action.ndim == 0 else action)
    batch = agent.predict(np.stack([obs, obs, obs]))
    assert batch.shape[0] == 3
    returns = agent.evaluate(env, episodes=2, seed=0).returns
    assert returns.shape == (2,) and np.isfinite(returns).all()
    assert np.array_equal(returns, agent.evaluate("GridWorld", episodes=2, seed=0).returns)
    assert np.array_equal(returns, agent.evaluate(agent.make_env, episodes=2, seed=0).returns)
    broken = tmp_path / "broken.zip"
    broken.write_text("not a zip")
    with pytest.raises(ValueError, match="not a zip file"):
        groupwise.load_agent(broken)
