"""Choosing the take-away agent among a finished session's rounds (issue 20; docs/app.md,
"Results"): each round's clip, the pick, and its refusals."""

import io
import json
import zipfile

from tests.unit.server.conftest import context_of, new_session
from tests.unit.server.test_session_end import finished_session


def test_the_person_picks_a_rounds_agent_and_the_download_holds_it(client):
    sid = finished_session(client)  # round 0 with feedback, round 1 on the frozen reward
    agent = client.get(f"/api/sessions/{sid}/agent").json()
    assert (agent["round"], agent["chosen_by"]) == (1, "last")  # the default: the last round
    assert [(r["round"], r["video"], r["checkpoint"]) for r in agent["rounds"]] == [
        (0, True, True),
        (1, True, True),
    ]
    clip = client.get(f"/api/sessions/{sid}/agent/rounds/0.mp4")
    assert clip.status_code == 200 and clip.headers["content-type"] == "video/mp4"

    picked = client.put(f"/api/sessions/{sid}/agent/round", json={"round": 0})
    assert picked.status_code == 200, picked.text
    assert (picked.json()["round"], picked.json()["chosen_by"]) == (0, "person")
    assert picked.json()["env_steps"] == agent["rounds"][0]["env_steps"]
    assert client.get(f"/api/sessions/{sid}/agent").json()["round"] == 0

    download = client.get(f"/api/sessions/{sid}/agent.zip")
    assert f"groupwise-agent-{sid}-round-0.zip" in download.headers["content-disposition"]
    directory = context_of(client).data_dir / "sessions" / sid
    with zipfile.ZipFile(io.BytesIO(download.content)) as archive:
        assert json.loads(archive.read("agent.json"))["round"] == 0
        policy = archive.read("policy.zip")
    assert policy == (directory / "checkpoints" / "round-0000" / "policy.zip").read_bytes()
    assert policy != (directory / "checkpoints" / "round-0001" / "policy.zip").read_bytes()
    # the agent's video is now round 0's clip
    assert client.get(f"/api/sessions/{sid}/agent.mp4").content == clip.content


def test_a_pick_is_refused_with_a_reason(client):
    sid = finished_session(client)
    unknown = client.put(f"/api/sessions/{sid}/agent/round", json={"round": 7})
    assert unknown.status_code == 404 and "no round 7" in unknown.json()["detail"]
    assert client.get(f"/api/sessions/{sid}/agent/rounds/7.mp4").status_code == 404
    directory = context_of(client).data_dir / "sessions" / sid
    (directory / "checkpoints" / "round-0000" / "policy.zip").unlink()
    gone = client.put(f"/api/sessions/{sid}/agent/round", json={"round": 0})
    assert gone.status_code == 409
    assert "round 0's checkpoint has no policy.zip" in gone.json()["detail"]
    agent = client.get(f"/api/sessions/{sid}/agent").json()
    assert agent["round"] == 1 and agent["rounds"][0]["checkpoint"] is False
    assert client.put(f"/api/sessions/{sid}/agent/round", json={"round": -1}).status_code == 422

    early = new_session(client, rounds=1)["id"]
    refused = client.put(f"/api/sessions/{early}/agent/round", json={"round": 0})
    assert refused.status_code == 409 and "finished" in refused.json()["detail"]
