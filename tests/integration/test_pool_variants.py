"""Pools sampled partly from biased variants of the policy (`LoopConfig.pool_variants`, issue
20; `pool.sources.PolicyVariants`): begin_round draws them from the round's sample stream,
the CLI runs with them, and without them a round is sampled from the policy alone."""

import dataclasses

import numpy as np
import pytest

from groupwise.cli import main
from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig
from groupwise.episodes.fragments import Trajectory
from groupwise.pool.sources import PolicyVariants, pool_sources
from groupwise.query.strategies import PairwiseQueries
from groupwise.run.round import begin_round
from groupwise.run.run import Run

TINY = RunConfig(
    loop=LoopConfig(
        env="GridWorld", comparisons=12, rounds=2, steps=2 * 256, eval_episodes=2, seed=5
    ),
    reward=RewardConfig(epochs=2, initial_epoch_multiplier=2),
    ppo=PPOConfig(n_envs=2, n_steps=128, batch_size=64, n_epochs=2, tensorboard=False),
)
VARIED = dataclasses.replace(TINY, loop=dataclasses.replace(TINY.loop, pool_variants=4))


def _episodes(cfg: RunConfig) -> tuple[Trajectory, ...]:
    offer = begin_round(Run.create(cfg), PairwiseQueries(), 6)
    return offer.pool.episodes


def test_a_round_draws_its_variants_and_samples_half_its_windows_from_them():
    assert pool_sources(VARIED.loop)[1] == PolicyVariants(4, 0.5, 0.5, 0.05)
    plain, varied = _episodes(TINY), _episodes(VARIED)
    assert {e.source for e in plain} == {0}
    assert {e.source for e in varied} == {0, 1, 2, 3, 4}  # the policy, then its 4 variants
    # half of the 2 × 12 windows the pool of 12 is chosen from, 3 a variant: one episode each
    assert [e.source for e in varied if e.source] == [1, 2, 3, 4]
    assert _same([e.actions for e in _episodes(VARIED)], [e.actions for e in varied])
    assert not _same([e.actions for e in plain], [e.actions for e in varied])


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
