"""research/walker_remedies.py: its setups are valid configs, its commands parse, its table
reads run folders as `groupwise case-study` writes them."""

import argparse
import json
from pathlib import Path
from types import ModuleType

import pytest
from tests.research.conftest import research_script

from groupwise.cli import build_parser
from groupwise.config import RunConfig


@pytest.fixture(scope="module")
def wr() -> ModuleType:
    return research_script("walker_remedies")


def test_every_setup_is_a_partial_config_and_the_baseline_is_the_recipe_itself(wr):
    default = RunConfig()
    assert default.merged(wr.SETUPS["baseline"]) == default
    for partial in wr.SETUPS.values():
        default.merged(partial)  # raises on a field that is not a config's
    assert set(wr.DEFAULT_SETUPS) <= set(wr.SETUPS)


def test_a_run_command_is_the_best_recipe_as_case_study_parses_it(wr, tmp_path):
    args = argparse.Namespace(preferences=None, rounds=5, steps=40000, pretrain_steps=100000)
    command = wr.run_command(
        "groupwise", "walker-splits", 3, tmp_path / "c.json", tmp_path / "r", args
    )
    parsed = build_parser().parse_args(command[1:])
    assert parsed.target == "walker-splits" and parsed.dm == "groupwise" and parsed.seed == 3
    assert parsed.preferences == 240 and parsed.pairs == "paper" and parsed.rounds == 5
    assert parsed.pretrain_steps == 100000 and parsed.pool_variants == 8
    assert parsed.teacher_error == 0.12 and parsed.ppo == "mujoco" and parsed.no_video


def _run(folder: Path, success: float, takeaway: float, rho: str) -> None:
    folder.mkdir(parents=True)
    summary = {"final": {"success_rate": success}, "takeaway": {"success_rate": takeaway}}
    (folder / "summary.json").write_text(json.dumps(summary))
    (folder / "case-study.csv").write_text(
        "round,reward_rank_rho,reward_split,reward_nonsplit,reward_stance\n"
        f"0,0.1,nan,0.2,nan\n1,{rho},0.5,0.25,0.75\n"
    )


def test_the_table_counts_successful_seeds_and_averages_the_last_rounds_diagnostic(wr, tmp_path):
    _run(tmp_path / "surf" / "walker-splits-groupwise-s0", 0.6, 0.4, "0.2")
    _run(tmp_path / "surf" / "walker-splits-groupwise-s1", 0.4, 0.8, "0.4")
    (tmp_path / "configs").mkdir()
    lines = wr.table(tmp_path)
    assert lines[2] == (
        "| surf | walker-splits | 0,1 | 1/2 | 1/2 | 0.300 | 0.500 / 0.250 / 0.750 |"
    )
    assert len(lines) == 3
