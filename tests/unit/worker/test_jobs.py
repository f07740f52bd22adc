"""The training worker's jobs, run in this process on real pools, PPO and checkpoints."""

import json

from tests.unit.server.conftest import context_of, new_session, run_worker_once


def test_a_round_without_judgements_still_trains(client):
    sid = new_session(client)["id"]
    run_worker_once(client)
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    run_worker_once(client)
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"], state["error"]) == ("preparing", 1, None)
    data = context_of(client).data_dir
    checkpoint = data / "sessions" / sid / "checkpoints" / "round-0000"
    record = json.loads((checkpoint / "state.json").read_text())["records"][0]
    assert record["round"] == 0 and record["pairs_total"] == 0


def test_a_failing_job_fails_its_session_only_and_retry_recovers(client):
    broken = new_session(client)["id"]
    healthy = new_session(client)["id"]
    data = context_of(client).data_dir
    blocker = data / "sessions" / broken
    blocker.parent.mkdir(parents=True, exist_ok=True)
    blocker.write_text("a file where the session's directory should be")

    run_worker_once(client)  # the broken one waited longest
    failed = client.get(f"/api/sessions/{broken}").json()
    assert failed["phase"] == "failed"
    assert failed["error"].startswith("preparing round 0 failed: FileExistsError")
    run_worker_once(client)  # the worker goes on with the others
    assert client.get(f"/api/sessions/{healthy}").json()["phase"] == "ready"

    blocker.unlink()
    assert client.post(f"/api/sessions/{broken}/retry").json()["phase"] == "preparing"
    run_worker_once(client)
    assert client.get(f"/api/sessions/{broken}").json()["phase"] == "ready"
