"""`groupwise case-study`: a tiny run per target writes its per-round CSV, the video and the
strip; bad input is one line and exit code 2."""

import csv
import json
import math

import numpy as np
import pytest
from PIL import Image

from groupwise.cli import build_parser, main
from groupwise.clips.video import probe
from groupwise.commands.case_study import CASE_STEPS_PER_ROUND, case_config
from groupwise.envs import TARGETS, horizon
from groupwise.run.run import CONFIG_FILE, RESULTS_FILE
from groupwise.study.case_studies.case_record import CaseRecord
from groupwise.study.case_studies.case_study import CASE_FILE, STRIP_FILE, SUMMARY_FILE, VIDEO_FILE
from groupwise.study.case_studies.splits_posture import replay_posture
from groupwise.study.case_studies.table import (
    curves_figure,
    markdown_row,
    strips_figure,
    summary_rows,
)

COLUMNS = [
    "round",
    "comparisons_total",
    "judgements_total",
    "pairs_total",
    "label_error_rate",
    "label_error_rate_total",
    "tied_share_total",
    "label_error_untied_total",
    "pool_score_sd",
    "pool_score_max",
    "env_steps",
    "target_score_mean",
    "target_score_std",
    "success_rate",
    "stretch_rate",
    "true_return_mean",
    "sample_s",
    "feedback_s",
    "reward_s",
    "ppo_s",
    "eval_s",
    "wall_s",
    "reward_rank_rho",
    "reward_split",
    "reward_nonsplit",
    "reward_stance",
]


def _case_study(out, target: str, dm: str, seconds: str, *extra: str) -> int:
    return main(
        [
            "case-study",
            "--target",
            target,
            "--dm",
            dm,
            "--preferences",
            "20",
            "--rounds",
            "2",
            "--steps",
            "2048",
            "--seconds",
            seconds,
            "--eval-episodes",
            "2",
            "--seed",
            "0",
            "--recipe",
            "paper",  # the tiny runs' numbers: no pre-training, no variants, the study's PPO
            "--out",
            str(out),
            "-q",
            *extra,
        ]
    )


def _rows(out) -> list[dict[str, str]]:
    with (out / CASE_FILE).open() as handle:
        reader = csv.DictReader(handle)
        assert reader.fieldnames == COLUMNS
        return list(reader)


@pytest.mark.slow  # a whole case study with its film (40 s); make test-slow runs it
def test_backflip_case_study_writes_rounds_video_and_strip(tmp_path, capsys):
    out = tmp_path / "backflip"
    assert _case_study(out, "hopper-backflip", "groupwise", "0.24") == 0
    assert "hopper-backflip:" in capsys.readouterr().out
    for name in (CASE_FILE, RESULTS_FILE, CONFIG_FILE, SUMMARY_FILE, VIDEO_FILE, STRIP_FILE):
        assert (out / name).is_file(), name
    rows = _rows(out)
    assert [int(r["round"]) for r in rows] == [0, 1]
    assert [int(r["comparisons_total"]) for r in rows] == [2, 20]  # 10 % in round 0
    # round 0's pool holds 4 behaviours, often without two disjoint groups: pairs may be 0
    assert 0 <= int(rows[0]["pairs_total"]) < int(rows[1]["pairs_total"])
    assert [int(r["env_steps"]) for r in rows] == [2048, 4096]
    for row in rows:
        assert 0.0 <= float(row["success_rate"]) <= 1.0
        tied, untied = float(row["tied_share_total"]), float(row["label_error_untied_total"])
        if int(row["pairs_total"]) == 0:
            assert math.isnan(tied) and math.isnan(untied)
        else:
            assert 0.0 <= tied <= 1.0 and (math.isnan(untied) or 0.0 <= untied <= 1.0)
        assert math.isfinite(float(row["target_score_mean"]))
        # the round's pool, scored (`pool_scores`): sd and best of its behaviours' scores
        spread, best = float(row["pool_score_sd"]), float(row["pool_score_max"])
        assert 0.0 <= spread <= 1e3 and math.isfinite(best)
        assert all(float(row[f"{phase}_s"]) > 0 for phase in ("sample", "reward", "ppo", "eval"))
        assert -1.0 <= float(row["reward_rank_rho"]) <= 1.0  # issue 41's diagnostic
        assert math.isnan(float(row["reward_split"]))  # the walker's postures only
    assert float(rows[1]["wall_s"]) > float(rows[0]["wall_s"])

    config = json.loads((out / CONFIG_FILE).read_text())["loop"]
    assert config["env"] == "Hopper-backflip" and config["decision_maker"] == "groupwise"
    assert config["fragment_length"] == 30 and config["steps"] == 4096
    saved = json.loads((out / CONFIG_FILE).read_text())
    assert saved["reward"]["use_actions"] is True  # recipe `paper`: [obs ; act], as published
    summary = json.loads((out / SUMMARY_FILE).read_text())
    assert summary["target"]["threshold"] == TARGETS["hopper-backflip"].threshold
    assert summary["final"]["score_mean"] == pytest.approx(float(rows[1]["target_score_mean"]))
    filmed = summary["filmed"]
    assert filmed["score"] == max(summary["final"]["scores"])

    png = curves_figure([out, out], tmp_path / "curves.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 5000
    strips = np.asarray(Image.open(strips_figure([out], tmp_path / "strips.png")))
    assert strips.shape[0] > 100 and strips.std() > 10  # the strip, titled
    succeeded = summary["final"]["success_rate"] >= 0.6
    cells = summary_rows([out, out])[0].split(" | ")
    assert cells[:3] == ["| hopper-backflip", "groupwise", "2"]
    assert cells[3] == f"**{2 * succeeded}/2**" and cells[6] == "20"
    spread = cells[8].split(" / ")  # the pools' sd in rounds 0–2: this run has two rounds
    assert float(spread[0]) >= 0 and float(spread[1]) >= 0 and spread[2] == "–"
    row = markdown_row(out).split(" | ")
    assert row[:3] == ["| hopper-backflip", "groupwise", "0"] and row[3] == "20"
    assert row[-3] == f"{round(summary['final']['success_rate'] * 2)}/2"

    video = probe(out / VIDEO_FILE)
    assert video.fps == pytest.approx(31.25)  # every 4th step of 0.008 s: real speed
    assert video.frames == math.ceil((horizon("Hopper-backflip") + 1) / 4)
    strip = np.asarray(Image.open(out / STRIP_FILE))
    assert strip.shape == (240, 5 * 240 + 4 * 4, 3)
    assert len(filmed["strip_seconds"]) == 5
    assert filmed["strip_seconds"][-1] - filmed["strip_seconds"][0] == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("target", "dm", "seconds"),
    [("walker-splits", "pairwise", "0.24"), ("halfcheetah-standup", "interactive", "1.5")],
)
def test_other_targets_and_decision_makers_run(tmp_path, target, dm, seconds):
    out = tmp_path / target
    research = tmp_path / "research.json"  # a partial config: research settings
    settings = {"reward": {"use_actions": True}, "ppo": {"n_epochs": 3}}
    research.write_text(json.dumps(settings))
    args = ("--no-video", "--config", str(research), "--ppo", "mujoco", "--pairs", "24")
    assert _case_study(out, target, dm, seconds, *args) == 0
    config = json.loads((out / CONFIG_FILE).read_text())
    assert config["loop"]["pair_cap"] == pytest.approx(24 / 20)
    assert config["reward"]["use_actions"] is True
    assert config["ppo"]["learning_rate"] == 3e-4 and config["ppo"]["net_arch"] == [64, 64]
    assert config["ppo"]["n_epochs"] == 3  # the file changes the preset --ppo picked
    rows = _rows(out)
    assert len(rows) == 2 and int(rows[1]["comparisons_total"]) == 20
    assert int(rows[1]["judgements_total"]) > 0
    assert int(rows[0]["pairs_total"]) <= 2 and int(rows[1]["pairs_total"]) <= 2 + 21
    assert not (out / VIDEO_FILE).exists()
    if target == "walker-splits":  # its last round's posture, over the evaluation episodes
        for row in rows:  # the learned reward on the policy's own postures (issue 41)
            assert math.isfinite(float(row["reward_nonsplit"]))
        chosen, shares = replay_posture(out)
        assert chosen == 1 and shares["steps"] == 2 * horizon("Walker2d-splits")
        assert 0.0 <= shares["all"] <= min(shares["split"], shares["upright"], shares["feet_2"])
    assert [f.name for f in CaseRecord.__dataclass_fields__.values()] == COLUMNS


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--target", "hopper-backflip", "--dm", "psychic"], "psychic"),
        (["--target", "cartwheel"], "invalid choice"),
        (["--target", "hopper-backflip", "--seconds", "0"], "> 0"),
        (["--target", "hopper-backflip", "--pairs", "0"], ">= 1"),
        (["--target", "walker-splits", "--pairs", "paper", "--training", "continuous"], "rounds"),
    ],
)
def test_bad_input_is_one_line_and_exit_code_2(tmp_path, capsys, args, message):
    try:
        code = main(["case-study", *args, "--out", str(tmp_path / "out"), "-q"])
    except SystemExit as exit_:  # argparse rejects bad choices and numbers itself
        code = exit_.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ('{"loop": {"env": "Hopper-v5"}}', "leave loop.env out of --config"),
        ('{"loop": {"pool_varients": 2}}', "pool_varients"),
        ('{"loop": {"rounds": 0}}', "rounds"),
        ("[1, 2]", "JSON object"),
        ("{not json", "is not JSON"),
    ],
)
def test_a_bad_config_file_is_one_line_and_exit_code_2(tmp_path, capsys, config, message):
    path = tmp_path / "research.json"
    path.write_text(config)
    args = ["--target", "hopper-backflip", "--config", str(path), "--out", str(tmp_path / "o")]
    assert main(["case-study", *args, "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_a_config_file_sets_research_fields_under_the_options_given():
    def config(*args: str, partial: dict | None = None):
        parsed = build_parser().parse_args(
            ["case-study", "--target", "hopper-backflip", "--out", "unused", *args]
        )
        return case_config(parsed, partial or {})

    default = config()
    assert (default.loop.rounds, default.loop.steps) == (10, 10 * CASE_STEPS_PER_ROUND)
    assert not default.reward.use_actions and default.loop.eval_episodes == 0
    five = config(partial={"loop": {"rounds": 5}, "reward": {"ensemble_size": 5}})
    assert (five.loop.rounds, five.loop.steps) == (5, 5 * CASE_STEPS_PER_ROUND)  # per round kept
    assert five.reward.ensemble_size == 5 and not five.reward.use_actions
    given = config("--rounds", "2", "--steps", "2048", partial={"loop": {"rounds": 5}})
    assert (given.loop.rounds, given.loop.steps) == (2, 4096)  # the options win
    ppo = config("--ppo", "mujoco", partial={"ppo": {"n_epochs": 3}}).ppo
    assert (ppo.learning_rate, ppo.n_epochs) == (3e-4, 3)  # the file changes the preset
