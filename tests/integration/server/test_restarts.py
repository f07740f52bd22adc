"""Crashes and restarts: nothing answered is lost, and the session carries on.

- a server stopped and started again on the same data resumes the same session;
- a server killed (SIGKILL) while clients submit judgements has stored every judgement it
  answered with a 2xx, and the round continues after a restart;
- a killed training worker fails its session with a clear error, and retry recovers.
"""

import os
import random
import signal
import threading
import uuid

import httpx
from tests.integration.server.conftest import TINY_FLAGS, TINY_SETTINGS, judgement, wait_until


def test_a_restarted_server_resumes_the_session(serve):
    first = serve("--env", "GridWorld", *TINY_FLAGS)
    first.wait_for("ready", 0)
    with first.client() as http:
        for body in (judgement(0, ["b1"], ["b2"]), judgement(0, ["b3", "b4"], ["b5"])):
            assert http.post(f"/api/sessions/{first.session}/judgements", json=body).is_success
    first.stop()

    second = serve("--env", "GridWorld", *TINY_FLAGS)
    assert "resuming" in second.output and second.session == first.session
    state = second.wait_for("ready", 0)
    assert state["counts"]["comparisons_round"] == 2
    with second.client() as http:
        assert http.post(f"/api/sessions/{second.session}/end-round").is_success
    second.wait_for("ready", 1)


def _submitter(url: str, answered: list[str], stop: threading.Event, seed: int) -> None:
    rng = random.Random(seed)
    with httpx.Client(base_url=url, timeout=10) as http:
        while not stop.is_set():
            left, right = rng.sample(range(16), 2)
            body = judgement(0, [f"b{left}"], [f"b{right}"], client_id=str(uuid.uuid4()))
            try:
                response = http.post(f"/api/sessions/{url.session}/judgements", json=body)
            except httpx.HTTPError:
                return  # the server is gone
            if response.is_success:
                answered.append(body["client_id"])


class _Target(str):
    session: str


def test_a_killed_server_keeps_every_answered_judgement(serve):
    server = serve("--env", "GridWorld", *TINY_FLAGS)
    server.wait_for("ready", 0)
    target = _Target(server.url)
    target.session = server.session
    answered: list[str] = []
    stop = threading.Event()
    threads = [
        threading.Thread(target=_submitter, args=(target, answered, stop, seed))
        for seed in range(4)
    ]
    for thread in threads:
        thread.start()
    wait_until(lambda: len(answered) >= 40, timeout=60, every=0.05)
    server.kill()  # mid-way: the submitters are still sending
    stop.set()
    for thread in threads:
        thread.join(timeout=30)

    again = serve("--env", "GridWorld", *TINY_FLAGS)
    assert again.session == server.session
    with again.client() as http:
        stored = {
            j["client_id"] for j in http.get(f"/api/sessions/{again.session}/judgements").json()
        }
        assert set(answered) <= stored, f"lost {len(set(answered) - stored)} answered judgements"
        state = again.wait_for("ready", 0)
        assert state["counts"]["comparisons_round"] == len(stored)
        more = http.post(
            f"/api/sessions/{again.session}/judgements", json=judgement(0, ["b0"], ["b1"])
        )
        assert more.status_code == 201
        ended = http.post(f"/api/sessions/{again.session}/end-round")
        assert ended.status_code == 200 and ended.json()["phase"] == "training"


def _group_gone(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return True
    return False


def test_a_killed_worker_fails_the_session_and_retry_recovers(serve):
    # one render process, so that the worker has children to leave behind
    server = serve(
        "--env", "GridWorld", *TINY_FLAGS, settings={**TINY_SETTINGS, "render_workers": 1}
    )

    def rendering() -> int | None:
        state = server.state()
        busy = state["phase"] == "preparing" and state["progress"]["phase"] == "clips"
        return httpx.get(f"{server.url}/api/health").json()["worker_pid"] if busy else None

    pid = wait_until(rendering, timeout=120, every=0.05)
    os.kill(pid, signal.SIGKILL)
    failed = wait_until(lambda: (s := server.state())["phase"] == "failed" and s, timeout=30)
    assert failed["error"] == "the training worker stopped (exit code -9)"
    assert wait_until(lambda: _group_gone(pid), timeout=10), "render processes outlived the worker"
    with server.client() as http:
        assert http.post(f"/api/sessions/{server.session}/end-round").status_code == 409
        retried = http.post(f"/api/sessions/{server.session}/retry")
        assert retried.status_code == 200 and retried.json()["phase"] == "preparing"
        assert retried.json()["error"] is None
    server.wait_for("ready", 0)
    new_pid = httpx.get(f"{server.url}/api/health").json()["worker_pid"]
    assert new_pid is not None and new_pid != pid


def test_a_worker_killed_mid_training_resumes_while_the_round_is_open(serve):
    """A continuous session's worker killed while the person compares: the supervisor starts
    another at once (the open round is work), which trains on from the checkpoint; the
    session never fails and the round stays open."""
    server = serve("--env", "GridWorld", *TINY_FLAGS, settings={**TINY_SETTINGS})
    server.wait_for("ready", 0)
    with server.client() as http:
        answer = http.post(
            f"/api/sessions/{server.session}/judgements",
            json=judgement(0, ["b0", "b1"], ["b2"]),
        )
        assert answer.status_code == 201, answer.text

        def steps() -> int:
            points = http.get(f"/api/sessions/{server.session}/training").json()["points"]
            return max((p["ppo_steps"] for p in points), default=0)

        wait_until(lambda: steps() > 0, timeout=120)  # PPO trains while the round is open
        pid = http.get("/api/health").json()["worker_pid"]
        os.kill(pid, signal.SIGKILL)
        restarted = wait_until(
            lambda: (p := http.get("/api/health").json()["worker_pid"]) not in (None, pid) and p,
            timeout=60,
        )
        assert restarted != pid
        before = len(http.get(f"/api/sessions/{server.session}/training").json()["points"])
        wait_until(  # the new worker refits and evaluates: new points of the curve
            lambda: (
                len(http.get(f"/api/sessions/{server.session}/training").json()["points"]) > before
            ),
            timeout=120,
        )
        state = server.state()
        assert (state["phase"], state["round"], state["error"]) == ("ready", 0, None)
