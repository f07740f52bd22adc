"""The Groupwise-DM's suggestions taken most promising first (`LoopConfig.suggestion_rank`,
issue 20): the registered DM and the app's list follow the config, a real round's first
query holds the group of the highest upper confidence bound, and the CLI sets it."""

import dataclasses

import numpy as np

from groupwise.cli import main
from groupwise.config import LoopConfig, RewardConfig, RunConfig
from groupwise.oracles import STRATEGIES
from groupwise.query.groups import group_upper_bound
from groupwise.query.strategies import GroupSuggestions, pool_candidates
from groupwise.run.round import begin_round
from groupwise.run.run import Run

TINY = RunConfig(
    loop=LoopConfig(env="GridWorld", comparisons=12, rounds=1, steps=0, eval_episodes=1, seed=3),
    reward=RewardConfig(epochs=1, initial_epoch_multiplier=1),
)
OPTIMISTIC = dataclasses.replace(
    TINY, loop=dataclasses.replace(TINY.loop, suggestion_rank="optimistic")
)


def test_the_groupwise_dm_follows_the_configured_rank():
    plain, optimistic = STRATEGIES["groupwise"](TINY), STRATEGIES["groupwise"](OPTIMISTIC)
    assert isinstance(plain, GroupSuggestions) and plain.rank == "variance"
    assert isinstance(optimistic, GroupSuggestions) and optimistic.rank == "optimistic"


def test_a_round_asks_first_about_the_most_promising_group():
    run = Run.create(OPTIMISTIC)
    offer = begin_round(run, STRATEGIES["groupwise"](OPTIMISTIC), 6)
    candidates = pool_candidates(offer.pool, OPTIMISTIC.tree)
    assert len(candidates) >= 3 and offer.queries
    membership = np.zeros((len(candidates), len(offer.pool)))
    for g, candidate in enumerate(candidates):
        membership[g, list(candidate.members)] = 1 / len(candidate.members)
    upper = group_upper_bound(offer.pool.predicted_returns, membership)
    first = offer.queries[0]
    best = candidates[int(upper.argmax())].members
    assert best in (first.left, first.right)
    plain = begin_round(Run.create(TINY), STRATEGIES["groupwise"](TINY), 6)
    assert [(q.left, q.right) for q in plain.queries] != [(q.left, q.right) for q in offer.queries]


def test_the_command_line_sets_the_rank(tmp_path):
    out = tmp_path / "train"
    args = ["--comparisons", "4", "--rounds", "1", "--steps", "0", "--seed", "1", "-q"]
    command = ["train", "--env", "GridWorld", "--dm", "groupwise", "--suggestions", "optimistic"]
    assert main([*command, "--out", str(out), *args]) == 0
    assert RunConfig.load(out / "config.json").loop.suggestion_rank == "optimistic"
