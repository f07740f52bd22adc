"""The kept policy (issue 39's tie trap): the person's answers on a pool that shows both the
kept policy's behaviours and PPO's latest decide which one PPO goes on from."""

import numpy as np
import pytest

from groupwise.behaviour.pool import BehaviourPool
from groupwise.config import LoopConfig, PPOConfig, RewardConfig
from groupwise.envs import make_env
from groupwise.episodes.fragments import Fragment
from groupwise.pool.recent import kept_tag, pool_ages
from groupwise.pool.sources import CurrentPolicy
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.preferences.pairs import Pair
from groupwise.reward import RewardEnsemble, fit
from groupwise.rl.ppo import PolicyState, PPOAgent
from groupwise.run.kept_policy import GO_BACK_P, KeptPolicy, decide, tag_rewards

ENV = "Pendulum-v1"
PPO = PPOConfig(n_envs=2, n_steps=64, batch_size=64, n_epochs=1, tensorboard=False)
LENGTH = 10
KEPT = 1  # the kept share's tag in a pool without variants
OBS = np.random.default_rng(0).uniform(-1, 1, (16, 3)).astype(np.float32)


def _agent() -> PPOAgent:
    return PPOAgent(lambda: make_env(ENV), PPO, seed=3)


def _actions(agent: PPOAgent) -> np.ndarray:
    return agent.act(OBS, np.random.default_rng(0), deterministic=True)


def _fragment(obs: float, episode: int) -> Fragment:
    rng = np.random.default_rng(episode)
    return Fragment(
        obs=(obs + 0.05 * rng.standard_normal((LENGTH, 3))).astype(np.float32),
        acts=np.zeros((LENGTH, 1), np.float32),
        true_rewards=np.zeros(LENGTH),
        episode=episode,
        start=0,
        reset_seed=episode,
    )


def _judged(prefer: int) -> tuple[BehaviourPool, RewardEnsemble]:
    """A round's pool of 6 fresh behaviours (tag 0, obs near +1) and 6 of the kept policy
    (obs near −1), and a reward ensemble fitted on answers that prefer tag `prefer`'s."""
    fragments = tuple(_fragment(1.0 if i < 6 else -1.0, i) for i in range(12))
    sources = np.array([0] * 6 + [KEPT] * 6)
    pool = BehaviourPool(1, fragments, np.zeros((12, 0)), sources=sources)
    pairs = [
        Pair(i, j, 1.0 if sources[i] == prefer else 0.0) for i in range(6) for j in range(6, 12)
    ]
    dataset = PreferenceDataset.empty(LENGTH, 3, 1)
    dataset.add(fragments, pairs, 1)
    cfg = RewardConfig(use_actions=False)
    ensemble = RewardEnsemble.for_env(lambda: make_env(ENV), cfg, np.random.default_rng(1))
    fit(ensemble, dataset, cfg, np.random.default_rng(2), epochs=30)
    return pool, ensemble


def _choice_after_a_round(agent: PPOAgent) -> KeptPolicy:
    """Kept the policy of round 0, PPO trained on, and round 1 cut with a kept share."""
    choice = KeptPolicy()
    assert choice.begin(agent, 0)
    assert not choice.begin(agent, 0)  # kept once
    agent.learn(2 * PPO.n_envs * PPO.n_steps, seed=1)
    # round 0's pool was the kept policy's own: nothing to compare
    round_0 = BehaviourPool(
        0, _judged(0)[0].fragments, np.zeros((12, 0)), sources=np.zeros(12, np.int64)
    )
    assert choice.choose(agent, _judged(0)[1], round_0, KEPT, 1) == "none"
    return choice


def test_a_policy_state_acts_and_learns_on_as_the_policy_did():
    agent = _agent()
    agent.learn(PPO.n_envs * PPO.n_steps, seed=1)
    state = agent.policy_state()
    before, steps = _actions(agent), agent.num_timesteps
    agent.learn(2 * PPO.n_envs * PPO.n_steps, seed=2)
    assert not np.array_equal(_actions(agent), before)
    snapshot = agent.snapshot(deterministic=True, state=state)
    assert np.array_equal(snapshot.act(OBS, np.random.default_rng(0)), before)
    agent.load_policy_state(state)
    assert np.array_equal(_actions(agent), before)
    assert agent.num_timesteps == steps + 2 * PPO.n_envs * PPO.n_steps  # steps still count


def test_a_policy_state_survives_its_file(tmp_path):
    agent = _agent()
    agent.learn(PPO.n_envs * PPO.n_steps, seed=1)
    state = agent.policy_state()
    state.save(tmp_path / "state.pt")
    loaded = PolicyState.load(tmp_path / "state.pt")
    fresh = _agent()
    fresh.load_policy_state(loaded)
    assert np.array_equal(_actions(fresh), _actions(agent))
    assert np.array_equal(loaded.obs_mean, state.obs_mean) and loaded.obs_count == state.obs_count


def test_the_answers_pay_each_source_what_they_preferred():
    pool, ensemble = _judged(KEPT)
    fresh, kept = tag_rewards(ensemble, pool, 0), tag_rewards(ensemble, pool, KEPT)
    assert fresh is not None and kept is not None
    assert fresh.shape == (3, int(np.sum(pool.sources == 0)))
    assert kept.shape == (3, int(np.sum(pool.sources == KEPT)))
    assert (kept.mean(axis=1) > fresh.mean(axis=1)).all()
    assert tag_rewards(ensemble, pool, 5) is None
    unknown = BehaviourPool(1, pool.fragments, pool.predicted_returns)
    assert tag_rewards(ensemble, unknown, 0) is None


def test_going_back_needs_every_member_and_more_than_chance():
    rng = np.random.default_rng(0)
    fresh = rng.normal(0.1, 0.05, (3, 30))
    clearly = rng.normal(0.3, 0.05, (3, 20))
    went, p = decide(fresh, clearly)
    assert went == "back" and p < 1e-6
    # every member pays the kept ones a hair more (the backflip's noise-sized margins), but
    # over behaviours that is chance: the kept policy stays, PPO goes on
    hair = fresh + 0.003
    went, p = decide(fresh, hair)
    assert bool((hair.mean(axis=1) > fresh.mean(axis=1)).all()) and p >= GO_BACK_P
    assert went == "kept"
    # a clear margin that one member disagrees with: no going back either
    split = clearly.copy()
    split[0] = rng.normal(0.0, 0.05, 20)
    assert decide(fresh, split)[0] == "kept"
    # one kept behaviour cannot show more than chance against a handful of fresh ones
    assert decide(fresh[:, :10], clearly[:, :1])[0] == "kept"
    assert decide(clearly, fresh)[0] == "latest"


def test_when_every_member_pays_the_kept_policy_more_ppo_goes_back_to_it():
    agent = _agent()
    first = _actions(agent)
    choice = _choice_after_a_round(agent)
    assert not np.array_equal(_actions(agent), first)
    assert choice.share(agent, LoopConfig(env=ENV), 0.2) is not None  # round 1 shows both
    pool, ensemble = _judged(KEPT)
    assert choice.choose(agent, ensemble, pool, KEPT, 2) == "back"
    assert np.array_equal(_actions(agent), first)
    # the next pool is the kept policy's own: no share of it beside
    assert choice.cut is choice.kept and choice.share(agent, LoopConfig(env=ENV), 0.2) is None
    # a cut of round 2 again (the one made ahead was dropped) decides nothing again
    agent.learn(PPO.n_envs * PPO.n_steps, seed=2)
    trained = _actions(agent)
    assert choice.choose(agent, ensemble, pool, KEPT, 2) == "none"
    assert np.array_equal(_actions(agent), trained)
    assert choice.share(agent, LoopConfig(env=ENV), 0.2) is not None


def test_when_the_answers_prefer_the_latest_policy_it_becomes_the_kept_one():
    agent = _agent()
    choice = _choice_after_a_round(agent)
    judged_policy = choice.cut
    later = _actions(agent)
    pool, ensemble = _judged(0)
    assert choice.choose(agent, ensemble, pool, KEPT, 2) == "latest"
    assert choice.kept is judged_policy is not None
    assert judged_policy.steps == 2 * PPO.n_envs * PPO.n_steps
    assert np.array_equal(_actions(agent), later)  # PPO goes on where it is


@pytest.mark.parametrize("share", [0.0, 0.2])
def test_the_kept_share_is_sampled_from_the_kept_policy_and_aged_from_it(share):
    agent = _agent()
    choice = _choice_after_a_round(agent)
    source = choice.share(agent, LoopConfig(env=ENV), share)
    if share == 0:
        assert source is None
        return
    assert isinstance(source, CurrentPolicy) and source.share == share
    assert source.policy is not None
    kept = choice.kept
    assert kept is not None
    kept_policy = agent.snapshot(state=kept.state)  # stochastic, as pools are sampled
    drawn = source.policy.act(OBS, np.random.default_rng(5))
    assert np.array_equal(drawn, kept_policy.act(OBS, np.random.default_rng(5)))
    assert not np.array_equal(drawn, agent.policy().act(OBS, np.random.default_rng(5)))
    fragments = tuple(_fragment(0.0, i) for i in range(4))
    pool = BehaviourPool(2, fragments, np.zeros((4, 0)), sources=np.array([0, 0, KEPT, KEPT]))
    now = agent.num_timesteps
    ages = pool_ages(pool, None, now, choice.sampled(KEPT))
    assert ages.tolist() == [0, 0, now - kept.steps, now - kept.steps]


def test_the_kept_policy_survives_a_checkpoint(tmp_path):
    agent = _agent()
    first = _actions(agent)
    choice = _choice_after_a_round(agent)
    choice.save(tmp_path)
    loaded = KeptPolicy()
    loaded.load(tmp_path)
    assert loaded.kept is not None and loaded.cut is not None
    assert (loaded.kept.steps, loaded.cut.steps) == (0, 2 * PPO.n_envs * PPO.n_steps)
    for policy, acts in ((loaded.kept, first), (loaded.cut, _actions(agent))):
        fresh = _agent()
        fresh.load_policy_state(policy.state)
        assert np.array_equal(_actions(fresh), acts)
    nothing = KeptPolicy()
    nothing.load(tmp_path / "none")
    assert nothing.kept is None


def test_the_kept_share_is_tagged_after_the_variants():
    assert kept_tag(LoopConfig(env=ENV)) == 1
    assert kept_tag(LoopConfig(env=ENV, pool_variants=8)) == 9
