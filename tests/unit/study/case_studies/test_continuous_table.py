"""The continuous-vs-rounds table reads timed case-study runs
(`study.case_studies.continuous_table`)."""

import csv
import json
from pathlib import Path
from typing import Any

import pytest

from groupwise.study.case_studies.continuous_table import (
    main,
    minutes_to_pass,
    read_run,
    read_table,
    success_at,
    variants,
)


def test_minutes_to_pass_is_the_first_round_with_enough_successful_episodes():
    assert minutes_to_pass([1.0, 2.0, 3.0], [0.2, 0.6, 1.0]) == 2.0
    assert minutes_to_pass([1.0, 2.0], [0.4, 0.4]) is None
    assert minutes_to_pass([], []) is None


def _run(
    tmp: Path,
    name: str,
    mode: str,
    clocks: list[str],
    success: list[float],
    ppo: dict[str, Any] | None = None,
    seed: int = 3,
) -> Path:
    run = tmp / name
    run.mkdir()
    target = {"name": "hopper-backflip", "unit": "turns", "threshold": 1.0}
    (run / "summary.json").write_text(json.dumps({"target": target, "env_steps": 4096}))
    config = {"training": {"mode": mode}, "loop": {"seed": seed}, "ppo": ppo or {}}
    (run / "config.json").write_text(json.dumps(config))
    for file, rows in (
        ("rounds.csv", [{"round": i, "clock_s": c} for i, c in enumerate(clocks)]),
        (
            "case-study.csv",
            [
                {
                    "round": i,
                    "env_steps": 2048 * (i + 1),
                    "target_score_mean": 0.5 + i,
                    "success_rate": s,
                }
                for i, s in enumerate(success)
            ],
        ),
    ):
        with (run / file).open("w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    return run


def test_a_run_is_read_with_its_clock_in_minutes(tmp_path):
    run = read_run(_run(tmp_path, "a", "continuous", ["60", "180"], [0.0, 0.8]))
    assert (run.mode, run.seed, run.minutes, run.scores) == (
        "continuous",
        3,
        (1.0, 3.0),
        (0.5, 1.5),
    )
    assert run.passed_at == 3.0


def test_a_run_without_a_timed_teacher_is_refused(tmp_path):
    with pytest.raises(ValueError, match="teacher-pace"):
        read_run(_run(tmp_path, "a", "rounds", ["", ""], [0.0, 0.0]))


def test_an_unfinished_run_is_one_line_of_error(tmp_path, capsys):
    (tmp_path / "running").mkdir()
    with pytest.raises(SystemExit) as exit_:
        main([str(tmp_path / "running")])
    assert exit_.value.code == 2
    assert "running: no summary.json (not a finished case-study run)" in capsys.readouterr().err


def test_the_table_says_when_a_mode_did_not_pass(tmp_path, capsys):
    runs = [
        _run(tmp_path, "c", "continuous", ["60", "120"], [0.0, 1.0]),
        _run(tmp_path, "r", "rounds", ["90", "300"], [0.0, 0.2]),
    ]
    assert main([str(r) for r in runs]) == 0
    out = capsys.readouterr().out
    continuous = "| hopper-backflip | continuous | as most | 1 | 4,096 | 1.50 ± 0.00 turns"
    assert f"{continuous} | 1/1 | 2.0 |" in out
    rounds = "| hopper-backflip | rounds | as most | 1 | 4,096 | 1.50 ± 0.00 turns | 0/1 |"
    assert f"{rounds} not passed within 5.0 min |" in out


def test_an_ablation_s_arm_is_a_group_of_its_own(tmp_path, capsys):
    """The ablation of issue 39: runs of the same mode that differ in one setting from most
    of the runs given are a row of their own, named by that setting."""
    runs = [
        _run(tmp_path, "s0", "continuous", ["600"], [0.0], {"standardise_reward": True}),
        _run(tmp_path, "s1", "continuous", ["600"], [0.0], {"standardise_reward": True}),
        _run(tmp_path, "r", "continuous", ["600"], [1.0], {"standardise_reward": False}),
    ]
    assert main([str(r) for r in runs]) == 0
    out = capsys.readouterr().out
    assert "| continuous | as most | 2 | 4,096 | 0.50 ± 0.00 turns | 0/2 |" in out
    arm = "| continuous | ppo.standardise_reward=False | 1 | 4,096 | 0.50 ± 0.00 turns | 1/1 |"
    assert f"{arm} 10.0 |" in out


def test_a_variant_is_what_a_run_changes_and_neither_its_seed_nor_its_mode(tmp_path):
    runs = [
        read_run(_run(tmp_path, "c", "continuous", ["60"], [0.0], {"gamma": 0.99})),
        read_run(_run(tmp_path, "r", "rounds", ["60"], [0.0], {"gamma": 0.99}, seed=4)),
        read_run(_run(tmp_path, "g", "continuous", ["60"], [0.0], {"gamma": 0.9})),
    ]
    assert variants(runs) == ["as most", "as most", "ppo.gamma=0.9"]


def test_success_at_a_mark_is_the_last_round_ended_by_it():
    minutes, success = [3.3, 6.7, 10.1, 13.4], [1.0, 0.2, 0.8, 0.0]
    assert success_at(minutes, success, 10) == 0.8  # 10.1 min: within the grace
    assert success_at(minutes, success, 7) == 0.2
    assert success_at(minutes, success, 3) is None  # no round had ended


def test_the_marks_table_counts_runs_passing_at_and_passed_by_each_mark(tmp_path, capsys):
    runs = [
        _run(tmp_path, "a", "continuous", ["300", "606", "1200"], [1.0, 0.2, 0.8], seed=0),
        _run(tmp_path, "b", "continuous", ["300", "606", "1200"], [0.0, 0.6, 0.4], seed=1),
        _run(tmp_path, "r", "rounds", ["400", "800", "1300"], [0.0, 1.0, 1.0]),
    ]
    assert main([*map(str, runs), "--marks", "10", "20"]) == 0
    out = capsys.readouterr().out
    assert "| passing at 10 min | passed by 10 min | passing at 20 min | passed by 20 min |" in out
    assert "| hopper-backflip | continuous | as most | 2 | 1/2 | 2/2 | 1/2 | 2/2 |" in out
    # rounds: the round ending at 13.3 min is after 10; the one at 21.7 after 20
    assert "| hopper-backflip | rounds | as most | 1 | 0/1 | 0/1 | 1/1 | 1/1 |" in out


def _table(path: Path, rows: list[dict[str, Any]]) -> Path:
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def _row(variant: str, seed: int, round_index: int, minute: float, success: float) -> dict:
    return {
        "target": "hopper-backflip", "training": "continuous", "variant": variant,
        "seed": seed, "round": round_index, "minute": minute, "env_steps": 1000 * (round_index + 1),
        "target_score": 2 * success, "success": success, "tied_share_total": 0.1,
    }  # fmt: skip


def test_a_tidy_rounds_table_is_read_back_as_its_runs(tmp_path, capsys):
    rows = [
        _row("kept", 0, 1, 6.0, 1.0),  # rows in any order
        _row("kept", 0, 0, 3.0, 0.4),
        _row("kept", 1, 0, 3.0, 0.0),
        _row("kept", 1, 1, 6.0, 0.0),
        _row("before", 0, 0, 3.0, 0.0),
    ]
    table = _table(tmp_path / "rounds.csv", rows)
    assert main(["--table", str(table), "--marks", "5", "10"]) == 0
    out = capsys.readouterr().out
    # the kept variant: seed 0 passes at 6 min (round 1), seed 1 never; by label, not "as most"
    assert "| hopper-backflip | continuous | kept | 2 | 0/2 | 0/2 | 1/2 | 1/2 |" in out
    assert "| hopper-backflip | continuous | before | 1 | 0/1 | 0/1 | 0/1 | 0/1 |" in out
    assert "| 0 | 2,000 | 0.80 (3.0), 2.00 (6.0) | 6.0 min |" in out


def test_a_table_without_a_column_is_one_line_of_error(tmp_path, capsys):
    rows = [{k: v for k, v in _row("kept", 0, 0, 3.0, 1.0).items() if k != "minute"}]
    with pytest.raises(SystemExit):
        main(["--table", str(_table(tmp_path / "rounds.csv", rows))])
    assert "no column minute" in capsys.readouterr().err


def test_runs_appended_to_a_tidy_table_read_back_as_they_were(tmp_path, capsys):
    """`--append-to` writes the rows `--table` reads: the same runs, named by `--variant`,
    appended in the table's own column order."""
    runs = [
        _run(tmp_path, "c", "continuous", ["60", "180"], [0.0, 0.8]),
        _run(tmp_path, "r", "rounds", ["90", "300"], [0.2, 1.0], seed=4),
    ]
    table = tmp_path / "rounds.csv"
    assert main([str(runs[0]), "--append-to", str(table), "--variant", "kept"]) == 0
    assert main([str(runs[1]), "--append-to", str(table), "--variant", "rounds"]) == 0
    assert "2 rounds of 1 runs appended" in capsys.readouterr().out
    rows = list(csv.DictReader(table.open()))
    assert [(r["training"], r["variant"], r["seed"], r["round"]) for r in rows] == [
        ("continuous", "kept", "3", "0"),
        ("continuous", "kept", "3", "1"),
        ("rounds", "rounds", "4", "0"),
        ("rounds", "rounds", "4", "1"),
    ]
    [read_c, read_r] = read_table(table)
    assert read_c.minutes == read_run(runs[0]).minutes and read_c.config == {"variant": "kept"}
    assert read_r.success == read_run(runs[1]).success and read_r.passed_at == 5.0


def test_rows_appended_to_an_older_table_follow_its_column_order(tmp_path):
    """A table written by hand in another order (the stand-up's first rows were) gets new
    rows under its own header, not under `write_table`'s."""
    run = _run(tmp_path, "c", "continuous", ["60"], [1.0])
    table = tmp_path / "rounds.csv"
    header = "success,minute,seed,round,variant,training,target,target_score,env_steps"
    table.write_text(header + "\n0.0,1.0,0,0,old,rounds,hopper-backflip,0.1,100\n")
    assert main([str(run), "--append-to", str(table), "--variant", "new"]) == 0
    lines = table.read_text().splitlines()
    assert lines[0] == header and len(lines) == 3
    assert lines[2] == "1.0,1.0,3,0,new,continuous,hopper-backflip,0.5,2048"
    assert [r.config["variant"] for r in read_table(table)] == ["old", "new"]
