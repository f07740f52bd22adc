"""Named study ablations: each changes one config field; cells, plans and the CLI carry them."""

import dataclasses

import numpy as np
import pytest

from groupwise.cli import main
from groupwise.config import LoopConfig, RunConfig
from groupwise.preferences.judgement import LEFT_BETTER, Judgement
from groupwise.run.pairs import round_pairs
from groupwise.study.simulation import runner
from groupwise.study.simulation.ablations import ABLATIONS, ablate
from groupwise.study.simulation.cells import Cell, planned_cells, write_plan
from groupwise.study.simulation.profiles import SESSION, SMOKE
from groupwise.study.simulation.runner import StudySpec, StudySummary

INTENDED = {
    "capped": {("loop", "pair_cap"): 1.0},
    "pairs2x": {("loop", "pair_oversample"): 2.0},
    "no-reward-norm": {("ppo", "normalize_reward"): False, ("ppo", "standardise_reward"): False},
    "obs-only": {("reward", "use_actions"): False},
    "calibrated": {("teacher", "label_error"): 0.12},
    "noiseless": {("teacher", "noise_sigma"): 0.0},
}


def _changes(before: RunConfig, after: RunConfig) -> dict[tuple[str, str], object]:
    old, new = dataclasses.asdict(before), dataclasses.asdict(after)
    return {
        (part, name): new[part][name]
        for part in old
        for name in old[part]
        if old[part][name] != new[part][name]
    }


def test_every_ablation_is_tested():
    assert set(INTENDED) == set(ABLATIONS)


@pytest.mark.parametrize("name", list(INTENDED))
@pytest.mark.parametrize("profile", [SESSION, SMOKE], ids=lambda p: p.name)
def test_an_ablation_changes_exactly_its_field(name, profile):
    default = profile.run_config("GridWorld", "groupwise", 3)
    ablated = profile.run_config("GridWorld", "groupwise", 3, name)
    assert _changes(default, ablated) == INTENDED[name]
    assert ablate(default, name) == ablated
    assert ablate(default, None) == default


def test_an_unknown_ablation_names_the_known_ones():
    with pytest.raises(ValueError, match="capped, pairs2x, no-reward-norm, obs-only"):
        SMOKE.run_config("GridWorld", "pairwise", 0, "triple")
    with pytest.raises(ValueError, match="triple"):
        StudySpec(SMOKE, ("GridWorld",), ("pairwise",), 1, ("triple",))
    with pytest.raises(ValueError, match="condition"):
        Cell("GridWorld", "pairwise", 0, "triple")


def test_round_pairs_with_oversampling_two_yields_twice_the_pairs():
    judgements = [
        Judgement((0, 1, 2), (3, 4), LEFT_BETTER),
        Judgement((5,), (6,), LEFT_BETTER),
        Judgement((7, 8), (9, 10, 11, 12), LEFT_BETTER),
    ]
    once = round_pairs(judgements, LoopConfig(), 0, 3, np.random.default_rng(0))
    twice = round_pairs(judgements, LoopConfig(pair_oversample=2.0), 0, 3, np.random.default_rng(0))
    assert len(once) == 3 + 1 + 4
    assert len(twice) == 2 * len(once)
    assert set(twice) >= {(5, 6, LEFT_BETTER)}
    cartesian = LoopConfig(pair_derivation="cartesian", pair_oversample=2.0)
    assert len(round_pairs(judgements, cartesian, 0, 3, np.random.default_rng(0))) == 2 * (
        6 + 1 + 8
    )


def test_a_main_cell_keeps_its_key_and_directory(tmp_path):
    cell = Cell("GridWorld", "pairwise", 0)
    assert cell.ablation is None
    assert cell.to_json() == {"env": "GridWorld", "dm": "pairwise", "seed": 0, "condition": "cells"}
    assert cell.directory(tmp_path) == tmp_path / "cells" / "GridWorld" / "pairwise" / "seed-0"
    assert SMOKE.run_config("GridWorld", "pairwise", 0, cell.ablation) == SMOKE.run_config(
        "GridWorld", "pairwise", 0
    )


def test_ablation_cells_live_in_their_own_directory_and_plan(tmp_path):
    spec = StudySpec(SMOKE, ("GridWorld",), ("pairwise",), 1, ("pairs2x", "no-reward-norm"))
    cells = spec.cells()
    assert [c.condition for c in cells] == ["cells", "pairs2x", "no-reward-norm"]
    directories = {c.directory(tmp_path).relative_to(tmp_path).parts[0] for c in cells}
    assert directories == {"cells", "pairs2x", "no-reward-norm"}
    assert cells[1].label == "GridWorld/pairwise/seed-0 (pairs2x)"
    write_plan(tmp_path, "smoke", cells)
    assert planned_cells(tmp_path) == sorted(cells)
    jobs = {job.cell.condition: job.config for job in runner.plan_jobs(spec, tmp_path)}
    assert jobs["pairs2x"].loop.pair_oversample == 2.0
    assert jobs["no-reward-norm"].ppo.normalize_reward is False
    assert jobs["cells"] == SMOKE.run_config("GridWorld", "pairwise", 0)


def test_cli_cap_pairs_is_an_alias_of_ablation_capped(tmp_path, monkeypatch, capsys):
    specs = []

    def run_study(spec, out, **_):
        specs.append(spec)
        return StudySummary(())

    monkeypatch.setattr(runner, "run_study", run_study)
    base = ["study", "--profile", "smoke", "--out", str(tmp_path), "-q"]
    assert main([*base, "--cap-pairs"]) == 0
    assert main([*base, "--ablation", "pairs2x", "capped", "--cap-pairs"]) == 0
    assert main(base) == 0
    assert [s.ablations for s in specs] == [("capped",), ("pairs2x", "capped"), ()]
