"""A smoke study on GridWorld: local process pool, skip and resume on rerun, the report, Ray,
an ablation."""

import csv
import json
import re

import numpy as np
import pytest

from groupwise.cli import main
from groupwise.run.headless import run_session
from groupwise.run.progress import OnRoundEnd
from groupwise.study.simulation.cells import Cell, is_done
from groupwise.study.simulation.profiles import SMOKE
from groupwise.study.simulation.runner import StudySpec, run_study
from groupwise.teachers import DECISION_MAKERS

DMS = tuple(dm for dm in SMOKE.dms if dm in DECISION_MAKERS)
SPEC = StudySpec(SMOKE, ("GridWorld",), DMS, seeds=2)
ROW = re.compile(r"(-?\d+\.\d) ± (\d+\.\d|–) \(n=(\d+)\)")


class Killed(Exception):
    pass


def _rows(directory) -> list[dict[str, str]]:
    with (directory / "rounds.csv").open() as handle:
        return list(csv.DictReader(handle))


def _kill_after_first_round(record) -> None:
    if record.round == 0:
        raise Killed


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The smoke study, with one cell killed after its first round before the study starts."""
    root = tmp_path_factory.mktemp("study")
    killed = Cell("GridWorld", DMS[0], 1)
    with pytest.raises(Killed):
        run_session(
            SMOKE.run_config(killed.env, killed.dm, killed.seed),
            killed.directory(root),
            show_progress=False,
            callback=OnRoundEnd(_kill_after_first_round),
        )
    first_row = _rows(killed.directory(root))[0]
    summary = run_study(SPEC, root, workers=2, show_progress=False)
    return root, summary, killed, first_row


def test_every_cell_runs_to_the_end(study):
    root, summary, _, _ = study
    assert summary.count("failed") == 0, [o.error for o in summary.failed]
    assert summary.count("done") == len(DMS) * 2
    for cell in SPEC.cells():
        directory = cell.directory(root)
        assert is_done(directory)
        rows = _rows(directory)
        assert [int(r["round"]) for r in rows] == [0, 1, 2]  # two rounds and the final PPO
        assert int(rows[-1]["comparisons"]) == 0


def test_a_killed_cell_resumes_from_its_checkpoint(study):
    root, _, killed, first_row = study
    # round 0 was not run again: even its wall times are the ones written before the kill
    assert _rows(killed.directory(root))[0] == first_row


def test_a_rerun_skips_finished_cells(study):
    root, _, _, _ = study
    seen = []
    summary = run_study(SPEC, root, workers=2, show_progress=False, on_cell=seen.append)
    assert summary.count("skipped") == len(SPEC.cells()) == len(seen)


def test_report_table_equals_the_cells_final_returns(study, capsys):
    root, _, _, _ = study
    assert main(["report", str(root)]) == 0
    report = (root / "report.md").read_text()
    table = report.split("## Final true return")[1].split("##")[0]
    row = next(line for line in table.splitlines() if line.startswith("| GridWorld |"))
    found = ROW.findall(row)
    assert len(found) == len(DMS)
    for dm, (mean, sd, n) in zip(DMS, found, strict=True):
        finals = [
            float(_rows(Cell("GridWorld", dm, seed).directory(root))[-1]["true_return_mean"])
            for seed in range(2)
        ]
        assert int(n) == 2
        assert float(mean) == pytest.approx(np.mean(finals), abs=0.051)
        assert float(sd) == pytest.approx(np.std(finals, ddof=1), abs=0.051)
    for png in ("curves.png", "pairs_errors.png", "normalised.png"):
        assert (root / png).stat().st_size > 1000
    assert "Missing cells\n\nNone" in report


def test_study_cli_rejects_an_unknown_dm_in_one_line(tmp_path, capsys):
    code = main(["study", "--dms", "psychic", "--out", str(tmp_path), "-q"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert "psychic" in err and len(err.splitlines()) == 1


def test_a_study_directory_keeps_its_profile(study, capsys):
    root, _, _, _ = study
    code = main(["study", "--profile", "quick", "--out", str(root), "-q"])
    assert code == 2
    assert "smoke" in capsys.readouterr().err


@pytest.mark.slow  # a local Ray cluster starts (2 min on 2 cores); make test-slow runs it
def test_cells_run_on_a_local_ray(study, tmp_path):
    pytest.importorskip("ray", reason="Ray is not installed (pip install groupwise[ray])")
    root, _, _, _ = study
    spec = StudySpec(SMOKE, ("GridWorld",), DMS[:1], seeds=2)
    summary = run_study(spec, tmp_path, workers=2, backend="ray", show_progress=False)
    assert summary.count("done") == 2, [o.error for o in summary.failed]
    for cell in spec.cells():
        assert is_done(cell.directory(tmp_path))
        # a cell gives the same results in a Ray worker as in the local pool
        ours, local = _rows(cell.directory(tmp_path)), _rows(cell.directory(root))
        assert [r["true_return_mean"] for r in ours] == [r["true_return_mean"] for r in local]


def test_an_ablation_runs_into_its_own_cells_and_the_report(tmp_path):
    args = ["--profile", "smoke", "--envs", "GridWorld", "--dms", "groupwise", "--seeds", "1"]
    out = ["--out", str(tmp_path), "--workers", "2", "-q"]
    assert main(["study", *args, "--ablation", "pairs2x", *out]) == 0
    default, doubled = (Cell("GridWorld", "groupwise", 0, c) for c in ("cells", "pairs2x"))
    assert is_done(default.directory(tmp_path)) and is_done(doubled.directory(tmp_path))
    assert doubled.directory(tmp_path).relative_to(tmp_path).parts[0] == "pairs2x"
    plan = json.loads((tmp_path / "study.json").read_text())
    assert {c["condition"] for c in plan["cells"]} == {"cells", "pairs2x"}
    config = json.loads((doubled.directory(tmp_path) / "config.json").read_text())
    assert config["loop"]["pair_oversample"] == 2.0
    # both cells are the same up to their first preference pairs, which the ablation doubles
    first = next(i for i, r in enumerate(_rows(default.directory(tmp_path))) if int(r["pairs"]))
    pairs = [int(_rows(c.directory(tmp_path))[first]["pairs"]) for c in (default, doubled)]
    assert pairs[1] == 2 * pairs[0] > 0
    assert main(["report", str(tmp_path)]) == 0
    section = (tmp_path / "report.md").read_text().split("## Ablations")[1]
    assert "| env | DM | default | pairs2x |" in section
    assert "| GridWorld | groupwise |" in section
