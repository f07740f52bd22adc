"""A continuous session's next round is cut from PPO's own latest rollouts when the round
ends (issue 39: fresh pools, `jobs.open_fresh`), opened before the ended round is committed;
the page's counter follows PPO rollout by rollout; Pause pauses PPO; a worker killed between
opening and committing commits on resume; a rounds-mode round opens with its own pool's
position."""

import dataclasses

from tests.unit.server.conftest import context_of, new_session, post_judgement, run_worker_once
from tests.unit.worker.conftest import training_session

from groupwise.pool.files import load_fragments
from groupwise.storage.sessions import get_round
from groupwise.storage.training import list_points
from groupwise.worker import continuous_round, jobs
from groupwise.worker.job import checkpoint_of, job_of
from groupwise.worker.process import Worker
from groupwise.worker.publishing import sampled_at

ROLLOUT = 32  # TINY's PPO: 1 env × 32 steps
SLICES = 12  # 384 steps of one GridWorld episode; the last rollout's 32 hold 3 windows of 10


def _training_session(client, slices: int = SLICES, **settings) -> tuple[str, Worker]:
    return training_session(client, slices, **settings)


def _pool_dir(client, sid: str, round_index: int):
    context = context_of(client)
    with context.db.read() as s:
        return context.data_dir / str(get_round(s, sid, round_index).pool_dir)


def _round_stats(client, sid: str, round_index: int) -> dict | None:
    with context_of(client).db.read() as s:
        return get_round(s, sid, round_index).stats


def test_the_next_pool_is_cut_from_the_latest_rollouts_when_the_round_ends(client):
    sid, worker = _training_session(client)
    training = worker.continuous._rounds[sid]
    recorded = training.continuous.recorder.recent(32)
    assert [len(e.trajectory) for e in recorded] == [SLICES * ROLLOUT]  # the one episode
    episode = recorded[0]
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    assert worker.run_next()  # the training job opens round 1, then commits round 0
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"], state["error"]) == ("ready", 1, None)
    published = load_fragments(_pool_dir(client, sid, 1))
    assert len(published) == 16
    # the behaviours the last rollout's policy played are windows of the episode PPO played,
    # as it played it; the rest was sampled from the policy as it is
    last = (SLICES - 1) * ROLLOUT
    recorded_windows = [f for f in published if f.reset_seed == episode.trajectory.reset_seed]
    assert 0 < len(recorded_windows) < len(published)
    for fragment in recorded_windows:
        window = slice(fragment.start, fragment.start + 10)
        assert (fragment.obs == episode.trajectory.obs[window]).all()
        assert episode.window_policy(fragment.start) == last
    # the pool's position: the policy of the oldest rollout a behaviour came from
    assert sampled_at(_pool_dir(client, sid, 1)) == last
    stats = _round_stats(client, sid, 0)
    assert stats is not None and stats["env_steps"] == SLICES * ROLLOUT  # nothing trained again
    assert not worker.run_next()  # no preparing job was needed


def test_each_point_carries_its_own_rounds_pool_position(client):
    sid, worker = _training_session(client, rounds=3)
    client.post(f"/api/sessions/{sid}/end-round")
    worker.run_next()  # round 1 open from round 0's rollouts, round 0 committed
    post_judgement(client, sid, ["b3"], ["b4", "b5"], round_index=1)
    for _ in range(SLICES):
        assert worker.train_continuous()
    client.post(f"/api/sessions/{sid}/end-round")
    worker.run_next()  # round 2 open from round 1's rollouts, round 1 committed
    with context_of(client).db.read() as s:
        points = list_points(s, sid)
    positions = [sampled_at(_pool_dir(client, sid, r)) for r in (0, 1, 2)]
    # each pool is at most one rollout older than the policy that opened its round (all of
    # round 2's sampled from the policy now when the last rollout held no whole window)
    assert positions[:2] == [0, (SLICES - 1) * ROLLOUT]
    assert positions[2] in ((2 * SLICES - 1) * ROLLOUT, 2 * SLICES * ROLLOUT)
    for r in (0, 1, 2):
        assert {p.pool_steps for p in points if p.round == r} == {positions[r]}, r
    # round 1's commit comes after round 2 opened, with round 1's pool position (not the
    # policy round 1 left, the position it used to carry)
    assert (points[-1].round, points[-1].pool_steps) == (1, positions[1])
    # so the summary the page shows is of round 2's point, not of that later record
    summary = client.get(f"/api/sessions/{sid}/training").json()["summary"]
    steps = max(p.ppo_steps for p in points)
    assert (summary["round"], summary["pool_age"]) == (2, steps - positions[2])


def test_a_rounds_mode_round_opens_with_its_own_pool_position(client):
    """In rounds mode PPO trains between the rounds and the next pool is sampled after it:
    the page's "Pool sampled … ago" of round 1 is 0 steps, not the steps round 0's pool is
    older than the policy (20,480 through the app before, issue 39)."""
    sid = new_session(client, training="rounds", rounds=3)["id"]
    run_worker_once(client)  # round 0 ready
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    client.post(f"/api/sessions/{sid}/end-round")
    run_worker_once(client)  # round 0 trained and committed
    run_worker_once(client)  # round 1 prepared from the policy round 0 left
    with context_of(client).db.read() as s:
        points = list_points(s, sid)
    trained = max(p.ppo_steps for p in points)
    assert trained > 0
    assert [(p.round, p.pool_steps) for p in points] == [(0, 0), (1, trained)]
    assert sampled_at(_pool_dir(client, sid, 1)) == trained
    summary = client.get(f"/api/sessions/{sid}/training").json()["summary"]
    assert (summary["round"], summary["pool_age"], summary["ppo_steps"]) == (1, 0, trained)
    assert summary["pairs"] == points[0].pairs > 0  # the fit round 1 opened with


def test_the_step_counter_moves_with_each_rollout_and_pause_stops_ppo(client, monkeypatch):
    monkeypatch.setattr(continuous_round, "PROGRESS_S", 0.0)
    sid, worker = _training_session(client, slices=2)
    training = worker.continuous._rounds[sid]
    with context_of(client).db.read() as s:
        newest = list_points(s, sid)[-1]
    assert newest.ppo_steps == training.run.agent.num_timesteps == 2 * ROLLOUT
    assert client.post(f"/api/sessions/{sid}/pause").status_code == 200
    assert not worker.train_continuous()  # paused: no PPO …
    assert training.run.agent.num_timesteps == 2 * ROLLOUT
    assert worker.continuous._rounds[sid] is training  # … and the run is kept for the resumption
    assert client.post(f"/api/sessions/{sid}/resume").status_code == 200
    assert worker.train_continuous()
    assert training.run.agent.num_timesteps == 3 * ROLLOUT


def _opened_not_committed(client):
    """A session whose round 0 ended and whose round 1 `jobs.open_fresh` opened from round
    0's rollouts, round 0 not yet committed: (sid, worker, context, job, the continuous
    training)."""
    sid, worker = _training_session(client, slices=2)
    client.post(f"/api/sessions/{sid}/end-round")
    context = context_of(client)
    job = job_of(context.db, sid)
    assert job is not None
    training = worker.continuous.take(job)
    render = worker._render_pool(job.settings.render_workers)
    try:
        assert jobs.open_fresh(job, context.db, context.data_dir, training.continuous, render)
    except BaseException:
        training.run.close()
        raise
    return sid, worker, context, job, training


def test_a_worker_killed_between_opening_and_committing_commits_on_resume(client):
    sid, worker, context, _job, training = _opened_not_committed(client)
    training.run.close()
    worker.continuous.close()  # killed here: round 1 open, round 0 not committed
    assert _round_stats(client, sid, 0) is None

    resumed = Worker(context.db, context.data_dir, poll_s=0.1)
    post_judgement(client, sid, ["b3"], ["b4", "b5"], round_index=1)
    assert resumed.train_continuous()  # commits round 0 first, then trains round 1
    stats = _round_stats(client, sid, 0)
    assert stats is not None and stats["round"] == 0
    assert (context.data_dir / checkpoint_of(sid, 0) / "state.json").is_file()
    again = resumed.continuous._rounds[sid]
    assert again.round == 1 and len(again.run.dataset) > stats["pairs_total"]


def test_a_round_checkpointed_but_not_recorded_keeps_its_checkpoint_on_resume(client):
    """Killed after `end_round` wrote round 0's checkpoint (and dropped the mid-round one) but
    before its record was stored: the resumed worker records it from the checkpoint instead
    of training round 0 again from round −1 (which would lose its PPO steps)."""
    sid, _worker, context, job, training = _opened_not_committed(client)
    ended = dataclasses.replace(job, round=0, phase="training")
    record = jobs.commit_round(ended, context.db, context.data_dir, None, training.continuous)
    training.run.close()
    assert record.env_steps > 0 and _round_stats(client, sid, 0) is None  # killed here

    resumed = Worker(context.db, context.data_dir, poll_s=0.1)
    assert resumed.train_continuous()
    assert _round_stats(client, sid, 0) == {**record.stats(), "pool_steps": 0}


def test_finish_now_opens_no_next_round(client):
    sid, worker = _training_session(client, slices=2, rounds=3)
    state = client.post(f"/api/sessions/{sid}/finish").json()
    assert (state["phase"], state["round"]) == ("training", 0)
    assert worker.run_next()  # round 0 committed, no round cut from its rollouts
    state = client.get(f"/api/sessions/{sid}").json()
    assert state["phase"] == "finishing"
    assert _round_stats(client, sid, 0) is not None
