"""The study's reference (PPO on the env's own reward) and the `dmc` profile's cells."""

import dataclasses
from pathlib import Path

import pytest

from groupwise.recipes import PPO_PRESETS
from groupwise.study.simulation.cells import Cell, discover_cells, env_directory
from groupwise.study.simulation.profiles import DMC, SMOKE
from groupwise.study.simulation.reference import train_on_true_reward


def _tiny(steps: int, final_steps: int, seed: int = 0):
    config = SMOKE.run_config("GridWorld", "pairwise", seed)
    loop = dataclasses.replace(config.loop, steps=steps, final_steps=final_steps)
    return dataclasses.replace(config, loop=loop)


def test_the_reference_trains_the_cells_whole_budget_and_evaluates_along_the_way():
    points = train_on_true_reward(_tiny(512, 256), every=256)
    assert [p.steps for p in points] == [256, 512, 768]
    assert all(p.env == "GridWorld" and p.seed == 0 for p in points)
    assert points == train_on_true_reward(_tiny(512, 256), every=256)  # seeded
    assert points != train_on_true_reward(_tiny(512, 256, seed=1), every=256)


def test_the_reference_refuses_an_empty_budget():
    with pytest.raises(ValueError, match="budget"):
        train_on_true_reward(_tiny(0, 0), every=256)


def test_dmc_cells_hold_every_dm_to_one_pair_per_comparison_with_mujoco_ppo():
    config = DMC.run_config("dm_control/walker-walk-v0", "groupwise", 1)
    assert (config.loop.comparisons, config.loop.pair_cap) == (100, 1.0)
    assert config.loop.steps + config.loop.final_steps == 300_000
    mujoco = dataclasses.replace(PPO_PRESETS["mujoco"], tensorboard=False)
    assert config.ppo == mujoco


def test_a_namespaced_envs_cells_live_in_one_directory_and_are_found_again(tmp_path: Path):
    cell = Cell("dm_control/walker-walk-v0", "groupwise", 1)
    directory = cell.directory(tmp_path)
    assert directory.parent.parent.name == env_directory(cell.env) == "dm_control--walker-walk-v0"
    directory.mkdir(parents=True)
    assert discover_cells(tmp_path) == [cell]
