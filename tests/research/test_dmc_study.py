"""research/dmc_study.py: it collects the study's cells and references as `groupwise study`
and `study.simulation.reference` write them, and its table and README check read them."""

import csv
from pathlib import Path
from types import ModuleType

import pytest
from tests.research.conftest import research_script

from groupwise.study.simulation.cells import env_directory
from groupwise.study.simulation.profiles import DMC, PAPER_DMS
from groupwise.study.simulation.reference import ReferencePoint, write_points


@pytest.fixture(scope="module")
def dmc() -> ModuleType:
    return research_script("dmc_study")


def test_its_envs_and_dms_are_the_profiles(dmc):
    assert dmc.ENVS == DMC.envs and dmc.DMS == PAPER_DMS


def _cell(out: Path, condition: str, env: str, dm: str, seed: int, returns: list[float]) -> None:
    folder = out / condition / env_directory(env) / dm / f"seed-{seed}"
    folder.mkdir(parents=True)
    with (folder / "rounds.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, ["round", "env_steps", "true_return_mean", "pairs_total"])
        writer.writeheader()
        for i, value in enumerate(returns):
            writer.writerow({"round": i, "env_steps": 1000 * (i + 1), "true_return_mean": value,
                             "pairs_total": 10 * i})  # fmt: skip
    (folder / "done.json").write_text("{}")


def test_the_table_shows_each_final_return_beside_the_reference(dmc, tmp_path):
    walker = dmc.ENVS[0]
    _cell(tmp_path, "cells", walker, "groupwise", 0, [5.0, 100.0])
    _cell(tmp_path, "cells", walker, "groupwise", 1, [5.0, 300.0])
    _cell(tmp_path, "noiseless", walker, "pairwise", 0, [1.0, 50.0])
    unfinished = tmp_path / "cells" / env_directory(walker) / "pairwise" / "seed-0"
    unfinished.mkdir(parents=True)  # no done.json: left out
    points = [ReferencePoint(walker, 0, s, r, 0.0) for s, r in ((500, 10.0), (1000, 400.0))]
    write_points(points, dmc.reference_dir(tmp_path, walker, 0) / "reference.csv")
    rows = dmc.collect(tmp_path, seeds=2)
    assert len(rows) == 2 + 2 + 2 + 2
    table = dmc.table(rows)
    spec, never = (line for line in table if line.startswith("| walker-walk-v0"))
    # pairwise, groupwise, interactive, the reference: mean ± sd of the final returns
    assert "| 2 | – | 200 ± 141 | – | 400 ± 0 | PEBBLE 453" in spec
    assert "| 1 | 50 ± 0 | – | – | 400 ± 0 |" in never
    assert dmc.figure(rows, tmp_path / "curves.png").stat().st_size > 0


def test_the_readme_check_fails_on_a_stale_table(dmc, tmp_path):
    walker = dmc.ENVS[0]
    _cell(tmp_path, "cells", walker, "groupwise", 0, [5.0, 100.0])
    dmc.write_rows(dmc.collect(tmp_path, seeds=1), tmp_path / "runs.csv")
    rows = list(csv.DictReader((tmp_path / "runs.csv").open()))
    fresh = "\n".join(dmc.table(rows))
    readme = tmp_path / "README.md"
    readme.write_text(f"# DMC\n\n<!-- dmc-table -->\n{fresh}\n<!-- /dmc-table -->\n")
    assert dmc.check(readme) == 0
    readme.write_text(readme.read_text().replace("100 ± 0", "101 ± 0"))
    assert dmc.check(readme) == 1
