"""The `groupwise` command line: errors are one line and exit code 2; a real run works."""

import os
import subprocess
import sys

import pytest

from groupwise.cli import main


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
        (["--env", "GridWorld", "--oracle", "psychic"], "psychic"),
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
