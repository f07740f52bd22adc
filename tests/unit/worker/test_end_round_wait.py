"""End round does not wait for the PPO rollout in progress (issue 39: End round → next round
≤ 2 s): a continuous round's slice stops its rollout once the round has ended, untrained, and
the step count stays a whole number of rollouts, so the recorded behaviours keep their ages.
"""

from tests.unit.server.conftest import context_of
from tests.unit.worker.conftest import training_session

from groupwise.pool.files import load_fragments
from groupwise.storage.sessions import get_round
from groupwise.worker import continuous_round
from groupwise.worker.jobs import OPENING_FILE

ROLLOUT = 32  # TINY's PPO: 1 env × 32 steps


def test_a_slice_stops_its_rollout_when_its_round_ends(client, monkeypatch):
    monkeypatch.setattr(continuous_round, "STOP_POLL_S", 0.0)
    sid, worker = training_session(client, slices=2)
    training = worker.continuous._rounds[sid]
    episode = training.continuous.recorder.running[0]
    assert len(episode.actions) == 2 * ROLLOUT
    # the round ends while a slice is in progress (here: just before its rollout)
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    context = context_of(client)
    assert continuous_round.train_slice(training, context.db, worker.continuous.evaluator)
    # one step taken, then the rollout dropped untrained: no PPO steps counted, no update
    assert training.run.agent.num_timesteps == 2 * ROLLOUT
    assert len(episode.actions) == 2 * ROLLOUT + 1
    assert episode.policy_steps[-1] == 2 * ROLLOUT  # played by the policy as it is now
    # the training job then opens the next round from the latest rollout at once
    assert worker.run_next()
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"]) == ("ready", 1)
    with context.db.read() as s:
        pool_dir = context.data_dir / str(get_round(s, sid, 1).pool_dir)
    assert len(load_fragments(pool_dir)) == 16
    opening = (pool_dir / OPENING_FILE).read_text()
    assert '"sample"' in opening and '"before"' in opening


def test_a_stopped_rollout_leaves_whole_rollouts_and_true_ages(client):
    """A rollout stopped part way: the step count goes back to the rollouts trained, and the
    next rollout, played by the same policy, carries that policy's step count, as the
    dropped steps do."""
    sid, worker = training_session(client, slices=2)
    training = worker.continuous._rounds[sid]
    calls = 0

    def stop() -> bool:
        nonlocal calls
        calls += 1
        return calls > 5

    assert not training.continuous.learn(ROLLOUT, stop)
    assert training.run.agent.num_timesteps == 2 * ROLLOUT
    assert training.continuous.learn(ROLLOUT)  # a whole rollout: trained
    assert training.run.agent.num_timesteps == 3 * ROLLOUT
    played = training.continuous.recorder.running[0].policy_steps
    dropped = len(played) - 3 * ROLLOUT
    assert dropped == 6
    assert played == [0] * ROLLOUT + [ROLLOUT] * ROLLOUT + [2 * ROLLOUT] * (dropped + ROLLOUT)
