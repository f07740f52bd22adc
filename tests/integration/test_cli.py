"""The `groupwise` command line: errors are one line and exit code 2; a real run works."""

import argparse
import json
import os
import subprocess
import sys

import pytest

from groupwise.cli import build_parser, main
from groupwise.config import RunConfig


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "groupwise.cli", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--env", "NoSuchEnv"], "NoSuchEnv"),
        (["--env", "GridWorld", "--comparisons", "0"], "comparisons"),
        (["--env", "GridWorld", "--rounds", "two"], "whole number"),
        (["--env", "GridWorld", "--dm", "psychic"], "unknown decision-maker 'psychic'"),
        (["--env", "GridWorld", "--oracle", "pairwise"], "--oracle"),  # the old name is gone
    ],
)
def test_bad_input_is_one_line_and_exit_code_2(tmp_path, capsys, args, message):
    try:
        code = main(["train", *args, "--out", str(tmp_path / "out"), "-q"])
    except SystemExit as exit_:  # argparse rejects malformed numbers itself
        code = exit_.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert message in err
    assert "Traceback" not in err


def test_unwritable_output_directory(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    result = _run("train", "--env", "GridWorld", "--out", str(blocker / "out"), "-q")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr.strip().count("\n") == 0 and "output directory" in result.stderr


def test_train_runs_end_to_end_from_the_command_line(tmp_path):
    result = _run(
        "train",
        "--env",
        "GridWorld",
        "--comparisons",
        "4",
        "--rounds",
        "2",
        "--steps",
        "0",
        "--seed",
        "1",
        "--out",
        str(tmp_path),
        "-q",
    )
    assert result.returncode == 0, result.stderr
    assert "rounds.csv" in result.stdout
    assert (tmp_path / "rounds.csv").is_file()


@pytest.mark.parametrize("command", ["train", "case-study"])
@pytest.mark.parametrize("option", ["--pretrain-steps", "--pool-variants"])
def test_a_negative_count_is_refused(tmp_path, capsys, command, option):
    first = ["--env", "GridWorld"] if command == "train" else ["--target", "hopper-backflip"]
    with pytest.raises(SystemExit) as exit_:
        main([command, *first, option, "-1", "--out", str(tmp_path), "-q"])
    assert exit_.value.code == 2
    assert ">= 0" in capsys.readouterr().err


def test_train_takes_research_settings_from_a_partial_config(tmp_path, capsys):
    """--config FILE: a partial JSON config merged over the defaults, the options given on
    the command line over it; an old run's config.json (removed fields and all) as well."""
    partial = tmp_path / "research.json"
    partial.write_text(json.dumps({"reward": {"ensemble_size": 2}, "loop": {"rounds": 3}}))
    out = tmp_path / "run"
    args = ["--comparisons", "4", "--steps", "0", "--seed", "1", "--pool-variants", "2", "-q"]
    assert main(["train", "--env", "GridWorld", "--config", str(partial), "--rounds", "1",
                 "--out", str(out), *args]) == 0  # fmt: skip
    cfg = RunConfig.load(out / "config.json")
    assert (cfg.reward.ensemble_size, cfg.loop.rounds, cfg.loop.pool_variants) == (2, 1, 2)
    assert cfg.ppo == RunConfig().ppo  # what the file leaves out keeps its default
    old = json.loads(cfg.to_json())
    old["loop"]["suggestion_rank"] = "variance"  # a config.json written before issue 38
    old["reward"]["exploration_bonus"] = 0.0
    (tmp_path / "old.json").write_text(json.dumps(old))
    again = tmp_path / "again"
    assert main(["train", "--env", "GridWorld", "--config", str(tmp_path / "old.json"),
                 "--out", str(again), *args]) == 0  # fmt: skip
    assert RunConfig.load(again / "config.json") == cfg
    (tmp_path / "bad.json").write_text(json.dumps({"reward": {"ensemble_size": 0}}))
    assert main(["train", "--env", "GridWorld", "--config", str(tmp_path / "bad.json"),
                 "--out", str(tmp_path / "bad"), *args]) == 2  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert "reward.ensemble_size" in err and len(err.splitlines()) == 1


def test_every_command_prints_its_help(capsys):
    # argparse %-formats help texts: a recipe's "5 % random actions" broke `train --help`
    # and `case-study --help` with a traceback
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    assert len(commands) > 5
    for command in commands:
        with pytest.raises(SystemExit) as exit_:
            main([command, "--help"])
        assert exit_.value.code == 0, command
        assert f"usage: groupwise {command}" in capsys.readouterr().out
