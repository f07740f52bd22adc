"""The study report on hand-written cells: tables, missing cells, the capped ablation."""

import dataclasses
import json
import math

import numpy as np
import pytest

from groupwise.cli import main
from groupwise.run.records import RoundRecord, write_records
from groupwise.study.simulation.cells import Cell, mark_done, write_plan
from groupwise.study.simulation.profiles import SMOKE
from groupwise.study.simulation.report import NoResultsError, write_report
from groupwise.study.simulation.results import load_results, merge_results

# (env, dm, seed) → final true return; rounds: 0 and 1 ask 2 and 14 comparisons, row 2 is
# the frozen-reward PPO row.
FINALS = {
    ("GridWorld", "pairwise", 0): 700.0,
    ("GridWorld", "pairwise", 1): 720.0,
    ("GridWorld", "groupwise", 0): 650.0,
    ("GridWorld", "groupwise", 1): 690.0,
    ("Hopper", "pairwise", 0): 100.0,
    ("Hopper", "pairwise", 1): 300.0,
    ("Hopper", "groupwise", 0): 500.0,
}


def _records(final: float, pairs_per_comparison: int) -> list[RoundRecord]:
    rows = []
    total = 0
    for index, (comparisons, ret) in enumerate([(2, final / 4), (14, final / 2), (0, final)]):
        pairs = comparisons * pairs_per_comparison
        total += pairs
        rows.append(
            RoundRecord(
                round=index,
                comparisons=comparisons,
                judgements=comparisons,
                pairs=pairs,
                pairs_total=total,
                label_error_rate=0.1,
                label_error_rate_total=0.1 * pairs_per_comparison,
                reward_loss=0.5,
                reward_accuracy=0.8,
                reward_val_accuracy=math.nan,
                env_steps=256 * (index + 1),
                true_return_mean=ret,
                true_return_std=1.0,
                sample_s=0.0,
                feedback_s=0.0,
                reward_s=0.0,
                ppo_s=0.0,
                eval_s=0.0,
            )
        )
    return rows


def _write_cell(root, cell: Cell, final: float, rows: int | None = None, done: bool = True):
    directory = cell.directory(root)
    directory.mkdir(parents=True)
    SMOKE.run_config(cell.env, cell.dm, cell.seed).save(directory / "config.json")
    records = _records(final, 1 if cell.dm == "pairwise" else 3)
    write_records(directory / "rounds.csv", records[: rows or len(records)])
    if done:
        mark_done(directory, {"cell": cell.to_json()})


@pytest.fixture
def study(tmp_path):
    for (env, dm, seed), final in FINALS.items():
        _write_cell(tmp_path, Cell(env, dm, seed), final)
    _write_cell(tmp_path, Cell("Hopper", "groupwise", 1), 900.0, rows=1, done=False)
    for env in ("GridWorld", "Hopper"):
        for seed in (0, 1):
            _write_cell(tmp_path, Cell(env, "groupwise", seed, "capped"), 400.0 + seed)
    planned = [Cell(env, dm, seed) for (env, dm, seed) in FINALS]
    write_plan(tmp_path, "smoke", [*planned, Cell("GridWorld", "groupwise", 2)])
    return tmp_path


def _table_row(report: str, env: str) -> list[str]:
    section = report.split("## Final true return")[1].split("##")[0]
    row = next(line for line in section.splitlines() if line.startswith(f"| {env} |"))
    return [cell.strip() for cell in row.strip("|").split("|")]


def test_results_are_dm_arrays_of_runs_by_envs(study):
    grid = load_results(study).grid("cells")
    assert grid.dms == ("pairwise", "groupwise")
    assert grid.envs == ("Hopper", "GridWorld")  # the paper's table order
    np.testing.assert_allclose(grid.values["pairwise"], [[100.0, 700.0], [300.0, 720.0]])
    # the unfinished Hopper/groupwise/seed-1 is not a final result
    np.testing.assert_allclose(grid.values["groupwise"], [[500.0, 650.0], [np.nan, 690.0]])


def test_report_tables_missing_cells_and_capped_ablation(study):
    path = write_report(study, bootstrap_reps=200)
    report = path.read_text()
    # columns: env, pairwise, pairwise (paper), groupwise, groupwise (paper)
    assert _table_row(report, "GridWorld") == [
        "GridWorld",
        "710.0 ± 14.1 (n=2)",
        "762 ± 85",
        "670.0 ± 28.3 (n=2)",
        "712 ± 23",
    ]
    assert _table_row(report, "Hopper")[3] == "500.0 ± – (n=1)"
    assert "| pairwise | 4 | 16.0 ± 0.0 | 400 |" in report
    assert "| groupwise | 3 | 48.0 ± 0.0 | 1209 |" in report
    assert "Hopper/groupwise/seed-1: unfinished, 1 of 3 rows" in report
    assert "GridWorld/groupwise/seed-2: not started" in report
    capped = report.split("## Capped preference pairs")[1]
    assert "pairwise: uncapped cells stand in" in capped
    assert "| groupwise vs pairwise |" in capped
    for png in ("curves.png", "pairs_errors.png", "normalised.png", "normalised_capped.png"):
        assert (study / png).stat().st_size > 1000
        assert f"]({png})" in report
    assert write_report(study, bootstrap_reps=200).read_text() == report  # seeded


def test_report_without_capped_cells_says_how_to_get_them(study):
    for directory in (study / "capped").glob("*/*/*"):
        (directory / "done.json").unlink()
    plan = json.loads((study / "study.json").read_text())
    assert plan["profile"] == "smoke"
    report = write_report(study, bootstrap_reps=50).read_text()
    assert "No finished capped cells" in report
    assert "--cap-pairs" in report
    assert "No finished ablation cells: `groupwise study --ablation NAME …`" in report


def _ablation_rows(report: str) -> dict[tuple[str, str], list[str]]:
    """The returns table of the Ablations section: (env, DM) → default, ablations …"""
    section = report.split("## Ablations")[1].split("\n## ")[0]
    table = next(block for block in section.split("\n\n") if block.startswith("| env |"))
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in table.splitlines()[2:]]
    return {(r[0], r[1]): r[2:] for r in rows}


def test_report_sets_each_ablation_beside_the_default_cells(study):
    for seed in (0, 1):
        _write_cell(study, Cell("GridWorld", "pairwise", seed, "pairs2x"), 710.0 + seed)
    _write_cell(study, Cell("GridWorld", "pairwise", 2, "pairs2x"), 0.0, rows=1, done=False)
    report = write_report(study, bootstrap_reps=50).read_text()
    section = report.split("## Ablations")[1].split("\n## ")[0]
    assert "| env | DM | default | capped | pairs2x |" in section
    assert "`pairs2x`: twice the preference pairs per judgement" in section
    assert "no-reward-norm" not in section  # no cell of it
    rows = _ablation_rows(report)
    # columns: default, capped, pairs2x; the unfinished pairs2x seed 2 does not count
    assert rows[("GridWorld", "pairwise")] == ["710.0 ± 14.1 (n=2)", "–", "710.5 ± 0.7 (n=2)"]
    assert rows[("GridWorld", "groupwise")] == ["670.0 ± 28.3 (n=2)", "400.5 ± 0.7 (n=2)", "–"]
    assert rows[("Hopper", "groupwise")] == ["500.0 ± – (n=1)", "400.5 ± 0.7 (n=2)", "–"]
    assert ("Hopper", "pairwise") not in rows  # no ablation ran it
    assert "| groupwise | 48.0 | 48.0 | – |" in section  # preference pairs per cell
    assert "GridWorld/pairwise/seed-2 (pairs2x): unfinished, 1 of 3 rows" in report


def test_an_empty_directory_has_no_report(tmp_path):
    with pytest.raises(NoResultsError):
        write_report(tmp_path)


def test_cell_directories_and_labels(tmp_path):
    cell = Cell("GridWorld", "pairwise", 3, "capped")
    assert cell.directory(tmp_path) == tmp_path / "capped" / "GridWorld" / "pairwise" / "seed-3"
    assert cell.label == "GridWorld/pairwise/seed-3 (capped)"
    assert Cell.from_json(cell.to_json()) == cell
    assert dataclasses.replace(cell, condition="cells").label == "GridWorld/pairwise/seed-3"


def test_two_studies_read_as_one(tmp_path):
    first, second = tmp_path / "session", tmp_path / "mujoco"
    for env, root in (("GridWorld", first), ("Hopper", second)):
        for seed in (0, 1):
            _write_cell(root, Cell(env, "pairwise", seed), 100.0 + seed)
            _write_cell(root, Cell(env, "groupwise", seed), 200.0 + seed)
    # capped groupwise cells in one study only; pairwise stands in per env, in both
    _write_cell(second, Cell("Hopper", "groupwise", 0, "capped"), 150.0)
    write_plan(first, "session", [Cell("GridWorld", "pairwise", 0)])
    write_plan(second, "mujoco", [Cell("Hopper", "pairwise", 0)])

    merged = merge_results([load_results(first), load_results(second)], tmp_path / "six")
    grid = merged.grid("cells")
    assert grid.envs == ("Hopper", "GridWorld") and merged.profile == "session + mujoco"
    capped, stand_ins = merged.capped_grid()
    assert capped.envs == ("Hopper",) and stand_ins == ("pairwise",)

    assert main(["report", str(tmp_path / "six"), "--from", str(first), str(second)]) == 0
    report = (tmp_path / "six" / "report.md").read_text()
    assert f"Study directories `{first}`, `{second}` as one, profile `session + mujoco`" in report
    assert _table_row(report, "Hopper")[0] == "Hopper" and _table_row(report, "GridWorld")
    assert not (tmp_path / "six" / "cells").exists()  # the report only

    with pytest.raises(ValueError, match=r"GridWorld/[a-z]+/seed-0 is in both"):
        merge_results([load_results(first), load_results(first)], tmp_path / "twice")
    assert main(["report", str(tmp_path / "x"), "--from", str(tmp_path / "nowhere")]) == 2
