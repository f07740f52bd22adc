"""Pools sampled partly from biased variants of the policy (`LoopConfig.pool_variants`, issue
20): begin_round draws them from the round's sample stream, the headless loop and the CLI
run with them, and without them a round is sampled as before."""

import dataclasses

import numpy as np
import pytest

from groupwise.cli import main
from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig
from groupwise.oracles import ORACLES, Feedback
from groupwise.preferences.judgement import Judgement
from groupwise.query.strategies import PairwiseQueries
from groupwise.rl.policy import BiasedPolicy
from groupwise.run.headless import run_session
from groupwise.run.round import begin_round, pool_variants, run_round
from groupwise.run.run import Run

TINY = RunConfig(
    loop=LoopConfig(
        env="GridWorld", comparisons=12, rounds=2, steps=2 * 256, eval_episodes=2, seed=5
    ),
    reward=RewardConfig(epochs=2, initial_epoch_multiplier=2),
    ppo=PPOConfig(n_envs=2, n_steps=128, batch_size=64, n_epochs=2, tensorboard=False),
)
VARIED = dataclasses.replace(TINY, loop=dataclasses.replace(TINY.loop, pool_variants=4))


def _actions(cfg: RunConfig) -> list[np.ndarray]:
    offer = begin_round(Run.create(cfg), PairwiseQueries(), 6)
    return [episode.actions for episode in offer.pool.episodes]


def test_a_round_draws_its_variants_and_samples_half_its_windows_from_them():
    run = Run.create(VARIED)
    policy = run.agent.policy()
    variants = pool_variants(run, policy, np.random.default_rng(0))
    assert len(variants) == 4 and all(isinstance(v, BiasedPolicy) for v in variants)
    assert all(v.base is policy and v.share == 0.5 for v in variants)  # pool_variant_scale
    assert pool_variants(Run.create(TINY), policy, np.random.default_rng(0)) == []
    plain, varied = _actions(TINY), _actions(VARIED)
    assert _same(_actions(VARIED), varied)  # the variants come from the round's stream
    assert not _same(plain, varied)


def _same(first: list[np.ndarray], second: list[np.ndarray]) -> bool:
    return len(first) == len(second) and all(
        np.array_equal(a, b) for a, b in zip(first, second, strict=True)
    )


def test_the_command_line_samples_from_variants(tmp_path):
    out = tmp_path / "train"
    args = ["--comparisons", "4", "--rounds", "1", "--steps", "0", "--seed", "1", "-q"]
    assert (
        main(["train", "--env", "GridWorld", "--pool-variants", "3", "--out", str(out), *args]) == 0
    )
    assert RunConfig.load(out / "config.json").loop.pool_variants == 3


def test_the_command_line_sets_the_pool_size(tmp_path):
    out = tmp_path / "train"
    args = ["--comparisons", "4", "--rounds", "1", "--steps", "0", "--seed", "1", "-q"]
    assert main(["train", "--env", "GridWorld", "--pool-size", "30", "--out", str(out), *args]) == 0
    cfg = RunConfig.load(out / "config.json")
    assert cfg.loop.pool_size == 30
    offer = begin_round(Run.create(cfg), PairwiseQueries(), 4)
    assert len(offer.pool.fragments) == 30  # not twice the round's 4 comparisons
    with pytest.raises(SystemExit):
        main(["train", "--env", "GridWorld", "--pool-size", "1", "--out", str(out), *args])


class PrefersVariants:
    """Prefers the group of later episodes: a pool lists the policy's episodes first."""

    def answer(self, pool, queries, rng):
        def lateness(group):
            return np.mean([pool.fragments[i].episode for i in group])

        return [
            Judgement(q.left, q.right, float(lateness(q.left) > lateness(q.right))) for q in queries
        ]


def test_the_policy_takes_the_push_of_the_variant_the_teacher_preferred(tmp_path):
    cfg = RunConfig(
        loop=LoopConfig(
            env="Pendulum-v1", comparisons=40, rounds=2, steps=2 * 256, eval_episodes=1,
            pool_variants=2, adopt_variants=True, initial_fraction=0.5, seed=2,
        ),
        reward=RewardConfig(epochs=1, initial_epoch_multiplier=1),
        ppo=PPOConfig(n_envs=2, n_steps=128, batch_size=64, n_epochs=1, tensorboard=False),
    )  # fmt: skip
    feedback = Feedback(ORACLES["pairwise"](cfg).queries, PrefersVariants())
    records = run_session(cfg, tmp_path, show_progress=False, feedback=feedback)
    assert all(r.adopted_variant in (1, 2) for r in records)
    unadopted = dataclasses.replace(cfg, loop=dataclasses.replace(cfg.loop, adopt_variants=False))
    plain = run_session(unadopted, tmp_path / "plain", show_progress=False, feedback=feedback)
    assert all(r.adopted_variant == 0 for r in plain)
    assert plain[0].label_error_rate == records[0].label_error_rate  # the same round 0


def test_the_command_line_adopts_and_looks_ahead_only_with_variants(tmp_path, capsys):
    out = tmp_path / "train"
    args = ["--comparisons", "4", "--rounds", "1", "--steps", "0", "--seed", "1", "-q"]
    assert main(["train", "--env", "Pendulum-v1", "--pool-variants", "2", "--adopt-variants",
                 "--out", str(out), *args]) == 0  # fmt: skip
    assert RunConfig.load(out / "config.json").loop.adopt_variants
    assert main(["train", "--env", "Pendulum-v1", "--adopt-variants", "--out", str(out / "x"),
                 *args]) == 2  # fmt: skip
    assert "pool_variants >= 1" in capsys.readouterr().err
    assert main(["train", "--env", "Pendulum-v1", "--pool-variants", "2", "--pool-lookahead",
                 "64", "--out", str(out / "ahead"), *args]) == 0  # fmt: skip
    assert RunConfig.load(out / "ahead" / "config.json").loop.pool_lookahead == 64
    assert main(["train", "--env", "Pendulum-v1", "--pool-lookahead", "64", "--out",
                 str(out / "y"), *args]) == 2  # fmt: skip
    assert "pool_lookahead needs" in capsys.readouterr().err


def test_greedy_variants_push_the_greedy_policy_and_the_first_does_not_push():
    cfg = RunConfig(
        loop=LoopConfig(env="Pendulum-v1", pool_variants=3, pool_variants_greedy=True, seed=1),
        ppo=PPOConfig(n_envs=1, n_steps=64, batch_size=32, tensorboard=False),
    )
    run = Run.create(cfg)
    variants = pool_variants(run, run.agent.policy(), np.random.default_rng(0))
    obs = np.random.default_rng(2).normal(size=(8, 3)).astype(np.float32)
    greedy = run.agent.act(obs, np.random.default_rng(0), deterministic=True)
    rng = np.random.default_rng(9)
    np.testing.assert_array_equal(variants[0].act(obs, rng), greedy)  # what the agent does
    plain = pool_variants(
        Run.create(
            dataclasses.replace(cfg, loop=dataclasses.replace(cfg.loop, pool_variants_greedy=False))
        ),
        run.agent.policy(),
        np.random.default_rng(0),
    )
    for variant, same_offset in zip(variants[1:], plain[1:], strict=True):  # the same draws
        np.testing.assert_array_equal(variant.offset, same_offset.offset)
        pushed = np.clip(greedy + variant.offset, -2.0, 2.0)
        np.testing.assert_allclose(variant.act(obs, rng), pushed, rtol=1e-6)
    with pytest.raises(ValueError, match="pool_variants_greedy needs"):
        LoopConfig(pool_variants_greedy=True)
    run.close()


def test_a_lookahead_varies_where_ppo_is_going_and_leaves_the_agent_as_it_was():
    cfg = RunConfig(
        loop=LoopConfig(
            env="Pendulum-v1", comparisons=4, pool_variants=3, pool_lookahead=128, seed=1
        ),
        reward=RewardConfig(epochs=2, initial_epoch_multiplier=1),
        ppo=PPOConfig(n_envs=1, n_steps=64, batch_size=32, tensorboard=False),
    )
    run = Run.create(cfg)
    obs = np.random.default_rng(2).normal(size=(8, 3)).astype(np.float32)
    stochastic = run.agent.act(obs, np.random.default_rng(0), deterministic=False)
    before = pool_variants(run, run.agent.policy(), np.random.default_rng(0))
    assert np.any(before[0].offset)  # no pairs yet: no lookahead, the first variant pushes
    run_round(run, ORACLES["pairwise"](cfg), 4, 0)  # the reward learns, PPO does not train
    variants = pool_variants(run, run.agent.policy(), np.random.default_rng(0))
    assert run.agent.num_timesteps == 0
    np.testing.assert_array_equal(  # the agent itself is as it was
        run.agent.act(obs, np.random.default_rng(0), deterministic=False), stochastic
    )
    np.testing.assert_array_equal(variants[0].offset, 0.0)  # the first pushes nothing ...
    ahead = variants[0].act(obs, np.random.default_rng(0))
    assert not np.allclose(ahead, stochastic)  # ... of a policy PPO has trained on
    again = pool_variants(run, run.agent.policy(), np.random.default_rng(0))
    np.testing.assert_array_equal(again[0].act(obs, np.random.default_rng(0)), ahead)  # seeded
    with pytest.raises(ValueError, match="pool_lookahead needs"):
        LoopConfig(pool_lookahead=10)
    run.close()
