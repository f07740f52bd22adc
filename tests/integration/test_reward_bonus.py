"""`--reward-bonus` and `--reward-pessimism`: a real run's reward checkpoints carry the fading
exploration bonus, or the lasting penalty on the members' disagreement."""

import pytest

from groupwise.cli import main
from groupwise.config import RunConfig
from groupwise.reward import RewardEnsemble
from groupwise.run.checkpoint import REWARD_FILE, checkpoint_dir


@pytest.mark.parametrize(
    ("option", "field", "per_round"),
    [
        ("--reward-bonus", "exploration_bonus", [2.0, 1.0]),  # halves each round
        ("--reward-pessimism", "pessimism", [-2.0, -2.0]),  # stays
    ],
)
def test_the_command_line_sets_the_weight_of_the_members_sd(tmp_path, option, field, per_round):
    out = tmp_path / "train"
    args = ["--comparisons", "20", "--rounds", "2", "--steps", "512", "--seed", "1", "-q"]
    command = ["train", "--env", "GridWorld", "--dm", "pairwise", option, "2"]
    assert main([*command, "--out", str(out), *args]) == 0
    assert getattr(RunConfig.load(out / "config.json").reward, field) == 2.0
    bonuses = [RewardEnsemble.load(checkpoint_dir(out, r) / REWARD_FILE).bonus for r in (0, 1)]
    assert bonuses == per_round


@pytest.mark.parametrize("value", ["-1", "nan", "inf", "x"])
def test_a_bad_bonus_is_refused_with_a_message(tmp_path, capsys, value):
    with pytest.raises(SystemExit) as exit_info:
        main(["train", "--env", "GridWorld", "--reward-bonus", value, "--out", str(tmp_path)])
    assert exit_info.value.code == 2
    assert "--reward-bonus" in capsys.readouterr().err
