"""The case-study table's summary: runs grouped by target and by the exploration they ran
with, and the pools' spread in rounds 0–2 averaged over the seeds."""

import csv
import json
from pathlib import Path

import numpy as np

from groupwise.study.case_studies.table import setup_label, summary_rows


def _run(
    path: Path,
    variants: int,
    pretrain: int,
    pool_sd: list[float] | None,
    rank: str = "variance",
    pool_size: int | None = None,
) -> Path:
    path.mkdir()
    final = {"success_rate": 0.6, "stretch_rate": 0.0}
    summary = {
        "target": {"name": "walker-splits"},
        "decision_maker": "groupwise",
        "final": final,
        "takeaway": final,
        "comparisons": 240,
        "preference_pairs": 600,
    }
    (path / "summary.json").write_text(json.dumps(summary))
    config = {
        "loop": {"pool_variants": variants, "suggestion_rank": rank, "pool_size": pool_size},
        "training": {"pretrain_steps": pretrain},
    }
    (path / "config.json").write_text(json.dumps(config))
    columns = ["round", "pairs_total"] + (["pool_score_sd", "pool_score_max"] if pool_sd else [])
    with (path / "case-study.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns)
        writer.writeheader()
        for r in range(len(pool_sd or [0.0, 0.0, 0.0])):
            row = {"round": r, "pairs_total": 100 * (r + 1)}
            if pool_sd:
                row |= {"pool_score_sd": pool_sd[r], "pool_score_max": 2 * pool_sd[r]}
            writer.writerow(row)
    return path


def test_runs_are_labelled_by_the_setup_they_ran_with(tmp_path):
    assert setup_label(_run(tmp_path / "a", 0, 0, None)) == "groupwise"
    assert setup_label(_run(tmp_path / "b", 8, 0, None)) == "groupwise · 8 pool variants"
    assert setup_label(_run(tmp_path / "c", 8, 100_000, None)) == (
        "groupwise · 8 pool variants · pre-training 100,000"
    )
    assert setup_label(_run(tmp_path / "e", 0, 0, None, pool_size=500)) == (
        "groupwise · pools of 500"
    )


def test_runs_of_removed_mechanisms_name_the_field_and_its_value(tmp_path):
    assert setup_label(_run(tmp_path / "d", 8, 0, None, "optimistic")) == (
        "groupwise · 8 pool variants · suggestion rank optimistic"
    )
    kept = _run(tmp_path / "f", 8, 0, None)
    config = json.loads((kept / "config.json").read_text())
    config["loop"] |= {"pool_variants_greedy": True, "pool_lookahead": 40_960}
    config["training"]["continue_from"] = "preferred"
    config["reward"] = {"pessimism": 1.0, "exploration_bonus": 0.0}  # a default: not named
    (kept / "config.json").write_text(json.dumps(config))
    assert setup_label(kept) == (
        "groupwise · 8 pool variants · pessimism 1 · pool variants greedy · pool lookahead "
        "40,960 · continue from preferred"
    )


def test_the_summary_averages_the_pools_of_each_setup_over_its_seeds(tmp_path):
    varied = [
        _run(tmp_path / "v0", 8, 0, [0.1, 0.2, 0.3]),
        _run(tmp_path / "v1", 8, 0, [0.3, 0.4]),  # a two-round run: round 2 from v0 alone
    ]
    plain = _run(tmp_path / "p0", 0, 0, None)  # predates the pool columns
    first, second = summary_rows([*varied, plain])
    cells = first.split(" | ")
    assert cells[1] == "groupwise · 8 pool variants" and cells[2] == "2"
    assert cells[8] == "0.20 / 0.30 / 0.30" and cells[9].rstrip(" |") == "0.40 / 0.60 / 0.60"
    assert second.split(" | ")[1] == "groupwise" and "– / – / –" in second


def test_the_curves_legend_grows_below_the_panels_and_never_over_them(tmp_path):
    from PIL import Image

    from groupwise.study.case_studies.table import Curve, target_curves_figure

    def drawn(keys: int) -> np.ndarray:
        curves = [
            Curve(target, 1.0, f"variant {k}", [1.0, 2.0, 3.0], [0.0, 1.0 + k, 2.0])
            for target in ("stand-up", "backflip")
            for k in range(keys)
        ]
        path = target_curves_figure(curves, tmp_path / f"{keys}.png", "minutes")
        return np.asarray(Image.open(path).convert("L"))

    few, many = drawn(2), drawn(12)
    # as wide, and taller by the legend's rows (inside the panels it grew over them)
    assert many.shape[1] == few.shape[1] and many.shape[0] > few.shape[0]
