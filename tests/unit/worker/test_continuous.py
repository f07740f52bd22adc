"""Continuous training in the app's worker (`worker.continuous`), in-process on a real database:
PPO trains while the round is open, the reward refits on the stored judgements, the round
ends on the run that trained, and a restarted worker resumes from the mid-round checkpoint."""

import json
import time
from datetime import timedelta

import pytest
from tests.unit.server.conftest import context_of, new_session, post_judgement, run_worker_once

from groupwise.storage.lifecycle import close_if_due
from groupwise.storage.models import utcnow
from groupwise.storage.sessions import round_directory
from groupwise.worker import continuous_round
from groupwise.worker.continuous_round import ContinuousTraining
from groupwise.worker.jobs import OPENING_FILE
from groupwise.worker.process import Worker

ROLLOUT = 32  # TINY's PPO: 1 env × 32 steps


def _worker(client) -> Worker:
    context = context_of(client)
    return Worker(context.db, context.data_dir, poll_s=0.1)


def _trained_once(client, budget: int) -> tuple[str, Worker, ContinuousTraining]:
    """A continuous session of `budget` comparisons a round, round 0 open with one
    judgement and one PPO rollout trained on it."""
    sid = new_session(client, training="continuous", comparisons_per_round=budget)["id"]
    run_worker_once(client)  # round 0 ready
    worker = _worker(client)
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    assert worker.train_continuous()
    return sid, worker, worker.continuous._rounds[sid]


def test_the_worker_trains_while_the_round_is_open_and_ends_it_on_that_run(client):
    sid = new_session(client, training="continuous")["id"]
    run_worker_once(client)  # round 0 ready
    worker = _worker(client)
    # an open continuous round with no pairs yet: no PPO, and the worker may sleep (it
    # used to report work done and poll the database in a tight loop)
    assert not worker.train_continuous()
    training = worker.continuous._rounds[sid]
    assert training.run.agent.num_timesteps == 0
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    for _ in range(3):
        assert worker.train_continuous()
    assert len(training.run.dataset) == 2  # the first pairs were fitted at once
    assert training.run.agent.num_timesteps == 3 * ROLLOUT
    post_judgement(client, sid, ["b3"], ["b4", "b5", "b6"])  # arrives between two slices …
    assert worker.train_continuous()
    assert training.run.agent.num_timesteps == 4 * ROLLOUT  # 3 new pairs: no refit yet
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    assert not worker.train_continuous()  # the round is no longer open
    assert worker.run_next()  # the training job ends the round on the run that trained …
    state = client.get(f"/api/sessions/{sid}").json()
    # … and opens the next one, cut from its rollouts: no preparing job
    assert (state["phase"], state["round"], state["error"]) == ("ready", 1, None)
    checkpoint = context_of(client).data_dir / "sessions" / sid / "checkpoints" / "round-0000"
    record = json.loads((checkpoint / "state.json").read_text())["records"][0]
    # … and is in the round's dataset; PPO's steps are those of the open round, no more
    assert record["pairs_total"] == 2 + 3
    assert record["env_steps"] == 4 * ROLLOUT


def test_a_restarted_worker_resumes_the_round_from_its_mid_round_checkpoint(client, monkeypatch):
    monkeypatch.setattr(continuous_round, "CHECKPOINT_S", 0.0)
    sid = new_session(client, training="continuous")["id"]
    run_worker_once(client)
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    first = _worker(client)
    for _ in range(2):
        first.train_continuous()
    assert first.continuous._rounds[sid].run.agent.num_timesteps == 2 * ROLLOUT
    post_judgement(client, sid, ["b7"], ["b8"])  # acknowledged, then the worker is killed
    second = _worker(client)  # a new worker: nothing in memory
    second.train_continuous()
    resumed = second.continuous._rounds[sid]
    assert resumed.run.agent.num_timesteps == 3 * ROLLOUT  # the checkpoint's 2, then 1 more
    assert len(resumed.run.dataset) == 2 + 1  # every acknowledged judgement's pairs


@pytest.mark.parametrize("training", ["rounds"])
def test_a_rounds_session_is_left_alone_while_open(client, training):
    sid = new_session(client, training=training)["id"]
    run_worker_once(client)
    post_judgement(client, sid, ["b0"], ["b1"])
    assert not _worker(client).train_continuous()


def test_sessions_take_turns_and_a_job_goes_first(client):
    """A continuous session's training blocks neither another's pool preparation (its job
    runs before the next slice) nor its training (the open sessions take turns)."""
    worker = _worker(client)
    first = new_session(client, training="continuous")["id"]
    assert worker.work_once()  # round 0 of the first session prepared
    post_judgement(client, first, ["b0", "b1"], ["b2"])
    assert worker.work_once()  # its first slice: fit and a rollout
    second = new_session(client, training="continuous")["id"]
    assert worker.work_once()  # the second session's preparation, before any more training
    assert client.get(f"/api/sessions/{second}").json()["phase"] == "ready"
    assert worker.continuous._rounds[first].run.agent.num_timesteps == ROLLOUT
    post_judgement(client, second, ["b3"], ["b4", "b5"])
    for _ in range(4):
        assert worker.work_once()
    steps = {sid: worker.continuous._rounds[sid].run.agent.num_timesteps for sid in (first, second)}
    assert steps == {first: 3 * ROLLOUT, second: 2 * ROLLOUT}  # turn by turn


def test_a_session_with_nothing_to_learn_from_passes_its_turn(client):
    idle = new_session(client, training="continuous")["id"]
    run_worker_once(client)
    busy = new_session(client, training="continuous")["id"]
    run_worker_once(client)
    post_judgement(client, busy, ["b0", "b1"], ["b2"])
    worker = _worker(client)
    for _ in range(2):
        assert worker.train_continuous()  # both slices go to the session with pairs
    assert worker.continuous._rounds[busy].run.agent.num_timesteps == 2 * ROLLOUT
    assert worker.continuous._rounds[idle].run.agent.num_timesteps == 0


def test_ppo_waits_for_the_last_comparison_only_while_the_cut_pool_stays_the_policys(
    client, monkeypatch
):
    """Issue 39: one short of the budget the next pool is cut and PPO waits; an undone
    judgement drops it (the end is no longer in sight), and so does a person who stops one
    short for `HOLD_S` (the agent trains on); the round's end then cuts the pool anew."""
    sid, worker, training = _trained_once(client, budget=3)
    second = post_judgement(client, sid, ["b3"], ["b4"])
    assert not worker.train_continuous()  # cut, and PPO waits
    assert training.staged is not None and training.run.agent.num_timesteps == ROLLOUT
    client.delete(f"/api/sessions/{sid}/judgements/{second['id']}")
    assert worker.train_continuous()  # two short again: PPO trains on, the cut dropped
    assert training.staged is None and training.run.agent.num_timesteps == 2 * ROLLOUT
    post_judgement(client, sid, ["b3"], ["b4"])
    assert not worker.train_continuous()  # cut again
    monkeypatch.setattr(continuous_round, "HOLD_S", 0.0)  # the person stopped one short
    assert worker.train_continuous()
    assert training.staged is None and training.declined == 2
    assert worker.train_continuous()  # not cut again at that count
    assert training.run.agent.num_timesteps == 4 * ROLLOUT
    post_judgement(client, sid, ["b5"], ["b6"])  # the budget: the round ends
    assert worker.run_next()
    opened = context_of(client).data_dir / round_directory(sid, 1)
    opening = json.loads((opened / OPENING_FILE).read_text())
    assert "staged_s" not in opening and "sample" in opening["parts_s"]
    worker.continuous.close()


def test_the_next_round_is_cut_as_many_comparisons_early_as_the_last_cut_took():
    ahead = continuous_round.comparisons_ahead
    assert ahead(None, [0.0, 5.0, 10.0]) == 1  # no cut measured yet
    assert ahead(9.0, [3.0]) == 1  # no pace yet
    assert ahead(9.0, [0.0, 5.0, 10.0]) == 2  # 9 s (+1) at 5 s a comparison
    assert ahead(3.0, [0.0, 10.0, 21.0]) == 1
    assert ahead(14.0, [0.0, 1.0, 100.0, 105.0, 110.0]) == 3  # the median gap: 5 s


def test_a_slow_cut_starts_before_the_last_comparison(client):
    sid, worker, training = _trained_once(client, budget=5)
    now = time.monotonic()
    training.cut_s = 100.0  # the last cut took 100 s, and the person takes 50 s a comparison
    training.judged_at = [now - 100.0, now - 50.0]
    post_judgement(client, sid, ["b3"], ["b4"])  # 3 short of the budget: (100 + 1) / 50 → 3
    assert not worker.train_continuous()
    assert training.staged is not None and training.staged_from == 2
    post_judgement(client, sid, ["b5"], ["b6"])
    assert not worker.train_continuous()  # PPO waits out the rest of the round
    assert training.run.agent.num_timesteps == ROLLOUT
    worker.continuous.close()


def test_a_round_its_timer_ends_is_cut_as_many_seconds_early_as_a_cut_takes(client):
    """Issue 39: a round with no comparison budget but a timer: a cut longer than the time
    left starts at once, PPO waits, and the timer's end opens the cut pool."""
    sid = new_session(client, training="continuous", comparisons_per_round=0, round_seconds=900)
    sid = sid["id"]
    run_worker_once(client)  # round 0 ready
    assert client.post(f"/api/sessions/{sid}/rounds/0/shown").status_code == 200  # timer runs
    worker = _worker(client)
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    assert worker.train_continuous()  # 900 s left, a cut of about a second: PPO trains
    training = worker.continuous._rounds[sid]
    assert training.staged is None and training.run.agent.num_timesteps == ROLLOUT
    training.cut_s = 1000.0  # the last cut took longer than the 900 s left
    assert not worker.train_continuous()  # cut now, and PPO waits for the timer
    assert training.staged is not None and training.run.agent.num_timesteps == ROLLOUT
    with context_of(client).db.write() as s:  # the timer runs out
        assert close_if_due(s, sid, utcnow() + timedelta(seconds=1000))
    assert worker.run_next()  # the round's job opens the cut pool
    assert client.get(f"/api/sessions/{sid}").json()["phase"] == "ready"
    opening = json.loads(
        (context_of(client).data_dir / round_directory(sid, 1) / OPENING_FILE).read_text()
    )
    assert "staged_s" in opening and "sample" not in opening["parts_s"]
    worker.continuous.close()


def test_the_minutes_log_line_says_where_the_time_went_and_the_longest_slice(client, caplog):
    sid, worker, training = _trained_once(client, budget=0)
    assert 0 < training.longest_slice_s < 60
    training.longest_slice_s = 99.0  # as if a slice had taken 99 s
    training.accounted -= continuous_round.ACCOUNT_S  # a minute has passed
    with caplog.at_level("INFO", logger="groupwise.worker.continuous_round"):
        assert worker.train_continuous()
    [line] = [r.getMessage() for r in caplog.records if "the longest slice" in r.getMessage()]
    assert f"session {sid} round 0" in line and "PPO" in line and "slice 99.0 s" in line
    assert training.longest_slice_s < 60  # counted anew for the next line: this slice
    worker.continuous.close()
