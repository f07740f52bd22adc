"""Envs that observe a dict, and the DeepMind Control suite, run through the command line;
observations that cannot be taught are refused there in one line, exit code 2 (issue 42)."""

import csv
import json

import numpy as np
import pytest
from tests.observation_envs import env_name

from groupwise.cli import main


def _train(tmp_path, env: str, *more: str) -> int:
    args = ["train", "--env", env, "--comparisons", "4", "--rounds", "1", "--steps", "512"]
    args += ["--recipe", "paper"]  # no pre-training on a MuJoCo env
    return main([*args, "--final-steps", "0", *more, "--out", str(tmp_path / "out"), "-q"])


def test_a_dict_observation_env_trains_a_round(tmp_path) -> None:
    assert _train(tmp_path, env_name("DictObs-v0"), "--seed", "2") == 0
    rows = list(csv.DictReader((tmp_path / "out" / "rounds.csv").open()))
    assert len(rows) == 1 and int(rows[0]["pairs_total"]) == 4
    assert json.loads((tmp_path / "out" / "config.json").read_text())["loop"]["env"] == env_name(
        "DictObs-v0"
    )


@pytest.mark.parametrize("command", ["train", "serve", "study"])
@pytest.mark.parametrize(
    ("gym_id", "reason"), [("ImageObs-v0", "is an image"), ("TextObs-v0", "is Text")]
)
def test_an_observation_that_cannot_be_taught_is_one_line_and_exit_code_2(
    tmp_path, capsys, command: str, gym_id: str, reason: str
) -> None:
    if command == "train":
        code = _train(tmp_path, env_name(gym_id))
    elif command == "serve":
        code = main(["serve", "--data", str(tmp_path / "data"), "--env", env_name(gym_id)])
    else:
        code = main(["study", "--envs", env_name(gym_id), "--out", str(tmp_path / "study")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert f"env {env_name(gym_id)} cannot be taught here: its observation {reason}" in err
    assert not (tmp_path / "data" / "groupwise.db").exists()
    assert not (tmp_path / "study").exists()


def test_a_dmc_id_trains_one_short_round(tmp_path) -> None:
    """Walker-walk through Shimmy: its dict observation flattened (height, orientations,
    velocity: 24 values), its 1,000-step horizon from the suite."""
    pytest.importorskip("shimmy", reason="the DeepMind Control suite needs groupwise[dmc]")
    pytest.importorskip("dm_control", reason="the DeepMind Control suite needs groupwise[dmc]")
    from groupwise.envs import horizon, make_env

    for name in ("dm_control/walker-walk-v0", "shimmy:dm_control/walker-walk-v0"):
        assert horizon(name) == 1000
    env = make_env("dm_control/walker-walk-v0")
    assert [leaf.name for leaf in env.leaves] == ["['height']", "['orientations']", "['velocity']"]
    obs, _ = env.reset(seed=0)
    assert obs.shape == (24,) and env.spec is not None and env.spec.max_episode_steps == 1000
    assert _train(tmp_path, "shimmy:dm_control/walker-walk-v0", "--seed", "1") == 0
    rows = list(csv.DictReader((tmp_path / "out" / "rounds.csv").open()))
    assert len(rows) == 1 and int(rows[0]["pairs_total"]) == 4
    assert np.isfinite(float(rows[0]["true_return_mean"]))
