"""`GET /api/sessions/{id}/training` and the ``training`` event: the worker's learning curve
of a continuous round (driven in-process, `Worker.train_continuous`) and of trained rounds."""

import json
import time

import anyio
import pytest
from tests.unit.server.conftest import context_of, new_session, post_judgement, run_worker_once

from groupwise.server.events import session_events
from groupwise.worker import curve
from groupwise.worker.process import Worker

ROLLOUT = 32  # TINY's PPO: 1 env × 32 steps


def _events(client, sid, last_event_id, count):
    """The first `count` events of the session's stream, as (event, data)."""

    async def read():
        context = context_of(client)
        stream = session_events(context.db, sid, 0.01, 60.0, last_event_id)
        events = []
        async for chunk in stream:
            text = chunk.decode()
            if text.startswith("event:"):
                head, data = text.strip().split("\ndata: ")
                events.append((head.split("\n")[0].removeprefix("event: "), json.loads(data)))
            if len(events) == count:
                return events
        return events

    return anyio.run(read)


def _curve_when(client, sid: str, evaluated: int) -> dict:
    """The session's curve once `evaluated` of its points have a true return (the evaluator
    process stores them as it finishes)."""
    deadline = time.monotonic() + 120
    while True:
        curve_ = client.get(f"/api/sessions/{sid}/training").json()
        if sum(p["true_return"] is not None for p in curve_["points"]) >= evaluated:
            return curve_
        assert time.monotonic() < deadline, curve_
        time.sleep(0.05)


def test_a_continuous_round_shows_its_steps_fits_and_true_returns(client, monkeypatch):
    monkeypatch.setattr(curve, "EVAL_MIN_S", 0.0)  # evaluate as soon as the last is done
    monkeypatch.setattr(curve, "EVAL_COST", 0.0)
    sid = new_session(client, training="continuous")["id"]
    run_worker_once(client)  # round 0 open
    assert client.get(f"/api/sessions/{sid}/training").json() == {"points": [], "summary": None}
    worker = Worker(context_of(client).db, context_of(client).data_dir, poll_s=0.1)
    try:
        worker.train_continuous()  # no pairs yet: no PPO, no point
        assert client.get(f"/api/sessions/{sid}/training").json()["points"] == []
        post_judgement(client, sid, ["b0", "b1"], ["b2"])
        # the first fit, the policy before any PPO handed to the evaluator process, a rollout
        # (the evaluator is still starting: no second evaluation yet)
        worker.train_continuous()
        _curve_when(client, sid, evaluated=1)
        worker.train_continuous()  # that evaluation is done: the next, after the second rollout
        curve_ = _curve_when(client, sid, evaluated=2)
        # the evaluator's return is the greedy policy's as the worker would measure it
        run = worker.continuous._rounds[sid].run  # its policy is still the one evaluated last
        loop = run.cfg.loop
        here = curve.true_return(
            run.make_env, run.agent.policy(True), loop.eval_episodes, loop.seed
        )
    finally:
        worker.continuous.close()
    points = curve_["points"]  # in time order: an evaluation's point as of its snapshot
    assert [(p["ppo_steps"], p["true_return"] is None) for p in points] == [
        (0, True),  # the first fit, stored at once
        (0, False),  # the policy before PPO, evaluated
        (2 * ROLLOUT, False),
    ]
    assert {(p["round"], p["pairs"], p["pool_steps"]) for p in points} == {(0, 2, 0)}
    assert points[-1]["true_return"] == pytest.approx(here, rel=1e-12)
    assert curve_["summary"] == {
        "round": 0,
        "ppo_steps": 2 * ROLLOUT,
        "pairs": 2,
        "reward_val_accuracy": points[-1]["reward_val_accuracy"],
        "pool_age": 2 * ROLLOUT,
        "true_return": points[-1]["true_return"],
    }
    # the stream sends the points written after the revision a page last saw
    revision = client.get(f"/api/sessions/{sid}").json()  # (no revision in the state)
    assert revision["phase"] == "ready"
    events = _events(client, sid, 0, 1 + 1 + len(points))  # state, judgement, points
    assert [name for name, _ in events] == [
        "state",
        "judgement",
        "training",
        "training",
        "training",
    ]
    assert [(d["ppo_steps"], d["true_return"] is None) for _, d in events[2:]] == [
        (0, True),
        (0, False),
        (2 * ROLLOUT, False),
    ]


@pytest.mark.parametrize("training", ["rounds", "continuous"])
def test_every_trained_round_adds_a_point_from_its_record(client, training):
    sid = new_session(client, training=training)["id"]
    run_worker_once(client)
    post_judgement(client, sid, ["b0"], ["b1"])
    assert client.post(f"/api/sessions/{sid}/end-round").status_code == 200
    run_worker_once(client)  # round 0 trained
    points = client.get(f"/api/sessions/{sid}/training").json()["points"]
    steps = 64 if training == "rounds" else 0  # TINY's ppo_steps_per_round; continuous: none
    record = points[-1]
    assert (record["round"], record["ppo_steps"], record["pairs"]) == (0, steps, 1)
    assert record["true_return"] is not None


def test_an_unknown_session_has_no_curve(client):
    assert client.get("/api/sessions/s-nope/training").status_code == 404
