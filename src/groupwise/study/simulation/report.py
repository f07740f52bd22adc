"""The study report: ``DIR/report.md`` and its PNGs, from the cells' ``rounds.csv`` (SPEC §8).

Sections: coverage; final true return per env and DM (mean ± SD over seeds, the paper's
table 1 beside it); preference pairs and label error rate per DM; training curves;
normalised final returns (per env, IQR ↦ [0, 1]) pooled over envs with Welch t-tests and
IQMs with stratified-bootstrap 95 % CIs; the capped-pairs ablation when its cells exist; every
ablation's final returns and pairs beside the default cells' (`ablations.ABLATIONS`); and
what is missing. Final results use finished cells only; curves also show unfinished ones.
"""

import logging
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from groupwise.study.simulation import figures, paper
from groupwise.study.simulation.ablations import ABLATIONS
from groupwise.study.simulation.cells import MAIN
from groupwise.study.simulation.figures import Band
from groupwise.study.simulation.report_tables import (
    DASH,
    finite_column,
    fmt_num,
    md_row,
    mean_sd_n,
    pooled_mean,
    tests_table,
)
from groupwise.study.simulation.results import Grid, StudyResults, load_results, merge_results
from groupwise.study.simulation.statistics import (
    confidence_band,
    iqm,
    iqr_normalise,
    mean_sd,
    stratified_bootstrap_ci,
)

log = logging.getLogger(__name__)

REPORT_FILE = "report.md"
CURVES_PNG = "curves.png"
PAIRS_PNG = "pairs_errors.png"
NORMALISED_PNG = "normalised.png"
CAPPED_PNG = "normalised_capped.png"


class NoResultsError(ValueError):
    """The directory holds no started study cell."""


def write_report(
    root: Path,
    seed: int = 0,
    bootstrap_reps: int = 2000,
    sources: Sequence[Path] = (),
) -> Path:
    """Write ``root/report.md`` and its figures; return the report's path.

    Args:
        seed: seeds the bootstrap, so the same cells give the same report.
        sources: study directories to read as one study (`merge_results`) instead of
            `root`'s own cells; `root` then only receives the report.
    Raises:
        NoResultsError: no cell under `root` (or `sources`) has started.
        ValueError: a cell's files cannot be parsed, or a cell is in two sources.
    """
    if sources:
        root.mkdir(parents=True, exist_ok=True)
        results = merge_results([load_results(s) for s in sources], root)
    else:
        results = load_results(root)
    if not results.records:
        raise NoResultsError(f"{root} holds no study cells (expected {root}/cells/ENV/DM/seed-K)")
    main_rng, capped_rng = np.random.default_rng(seed).spawn(2)
    grid = results.grid(MAIN)
    sections = [
        _header(results),
        _returns_table(grid),
        _pairs_section(results, root),
        _diagnostics_section(results),
        _curves_section(results, root),
        _normalised_section(
            grid,
            "Normalised final returns",
            None,
            paper.NORMALISED_TESTS,
            main_rng,
            bootstrap_reps,
            root / NORMALISED_PNG,
        ),
        _capped_section(results, capped_rng, bootstrap_reps, root),
        _ablations_section(results),
        _missing_section(results),
    ]
    path = root / REPORT_FILE
    path.write_text("\n\n".join(s.rstrip() for s in sections if s) + "\n")
    log.info("report: %s", path)
    return path


def _header(results: StudyResults) -> str:
    total = len(set(results.planned) | set(results.records))
    done = sum(r.complete for r in results.records.values())
    profile = results.profile or "unknown (no study.json)"
    where = f"Study directory `{results.root}`"
    if results.sources:
        where = "Study directories " + ", ".join(f"`{s}`" for s in results.sources) + " as one"
    return (
        "# Simulated study report\n\n"
        f"{where}, profile `{profile}`: {done} of {total} cells "
        f"finished, {len(results.unfinished())} unfinished, "
        f"{len(results.not_started())} not started. Final results use finished cells only."
    )


def _returns_table(grid: Grid) -> str:
    title = "## Final true return\n\nMean ± SD over seeds (n = finished seeds), after the last "
    title += "row of each cell; the paper's table 1 beside ours."
    if not grid.dms:
        return title + "\n\nNo finished cell yet."
    header = ["env"]
    for dm in grid.dms:
        header += [dm, f"{dm} (paper)"] if _in_paper(dm) else [dm]
    lines = [md_row(header), md_row(["---"] * len(header))]
    for j, env in enumerate(grid.envs):
        row = [env]
        for dm in grid.dms:
            column = grid.values[dm][:, j]
            n = int(np.isfinite(column).sum())
            mean, sd = mean_sd(column)
            row.append(f"{fmt_num(mean, 1)} ± {fmt_num(sd, 1)} (n={n})" if n else DASH)
            if _in_paper(dm):
                cited = paper.TABLE1.get(env, {}).get(dm)
                row.append(f"{cited[0]:g} ± {cited[1]:g}" if cited else DASH)
        lines.append(md_row(row))
    return title + "\n\n" + "\n".join(lines)


def _pairs_section(results: StudyResults, root: Path) -> str:
    pairs, errors = results.grid(MAIN, "final_pairs"), results.grid(MAIN, "final_error_rate")
    title = "## Preference pairs and label error rate\n\nPer finished cell at its end, pooled "
    title += "over envs and seeds (mean ± SD); the error rate is the share of pairs whose label "
    title += "disagrees with the true returns."
    if not pairs.dms:
        return title + "\n\nNo finished cell yet."
    lines = [
        md_row(["DM", "runs", "preference pairs", "paper", "label error rate"]),
        md_row(["---"] * 5),
    ]
    for dm in pairs.dms:
        n = int(np.isfinite(pairs.values[dm]).sum())
        p_mean, p_sd = mean_sd(pairs.values[dm])
        e_mean, e_sd = mean_sd(errors.values[dm])
        cited = paper.PREFERENCE_PAIRS.get(dm)
        lines.append(
            md_row(
                [
                    dm,
                    str(n),
                    f"{fmt_num(p_mean, 1)} ± {fmt_num(p_sd, 1)}",
                    f"{cited:g}" if cited is not None else DASH,
                    f"{fmt_num(e_mean, 3)} ± {fmt_num(e_sd, 3)}",
                ]
            )
        )
    tests = tests_table(
        {dm: pairs.values[dm] for dm in pairs.dms}, pairs.dms, paper.PAIR_TESTS, digits=1
    )
    figures.pairs_and_errors(
        pairs.envs,
        {dm: np.nanmean(_nan_safe(pairs.values[dm]), axis=0) for dm in pairs.dms},
        {dm: np.nanmean(_nan_safe(errors.values[dm]), axis=0) for dm in errors.dms},
        root / PAIRS_PNG,
    )
    return (
        f"{title}\n\n" + "\n".join(lines) + "\n\nWelch t-tests of the pair counts:\n\n"
        f"{tests}\n\n![pairs and error rate per env]({PAIRS_PNG})"
    )


def _diagnostics_section(results: StudyResults) -> str:
    fields = ("mean_asked", "mean_unused", "mean_skipped", "mean_judged", "mean_candidates")
    grids = {f: results.grid(MAIN, f) for f in fields}
    signal = results.grid(MAIN, "mean_signal")
    title = (
        "## How the queries went\n\nPer feedback round, mean over finished seeds: queries "
        "asked / left unused (the strategy had nothing to propose) / skipped (asked, no "
        "judgement) / judged; group candidates the tree offered; the pool's sd of true "
        "returns ÷ the per-behaviour noise sd L·σ. Below 1 the labels are near coin flips "
        "whatever the DM: an information limit, not a bug."
    )
    asked = grids["mean_asked"]
    if not asked.dms or not any(np.isfinite(v).any() for v in asked.values.values()):
        return title + "\n\nNo finished cell recorded these yet."
    lines = [
        md_row(["env", "DM", "asked / unused / skipped / judged", "candidates", "sd ÷ noise"]),
        md_row(["---"] * 5),
    ]
    limited = set()
    for j, env in enumerate(asked.envs):
        for dm in asked.dms:
            means = {f: _finite_mean(grids[f].values[dm][:, j]) for f in fields}
            ratio = _finite_mean(signal.values[dm][:, j])
            if ratio < 1:
                limited.add(env)
            counts = " / ".join(
                fmt_num(means[f], 1)
                for f in ("mean_asked", "mean_unused", "mean_skipped", "mean_judged")
            )
            lines.append(
                md_row([env, dm, counts, fmt_num(means["mean_candidates"], 1), fmt_num(ratio, 2)])
            )
    note = ""
    if limited:
        note = (
            f"\n\nAt the information limit (sd ÷ noise < 1): {', '.join(sorted(limited))}. "
            "Label errors there say more about the noise model than about the DMs."
        )
    return f"{title}\n\n" + "\n".join(lines) + note


def _curves_section(results: StudyResults, root: Path) -> str:
    panels: dict[str, dict[str, Band]] = {}
    for env in results.envs(MAIN):
        for dm in results.dms(MAIN):
            curves = results.curves(MAIN, env, dm)
            if curves is not None:
                mean, low, high = confidence_band(curves.returns)
                panels.setdefault(env, {})[dm] = Band(curves.steps, mean, low, high)
    if not panels:
        return ""
    figures.training_curves(panels, results.dms(MAIN), root / CURVES_PNG)
    return (
        "## Training curves\n\nTrue return (evaluation after every round) against PPO env "
        "steps; mean over seeds with a 95 % Student-t band. Unfinished cells count as far as "
        f"they got.\n\n![training curves]({CURVES_PNG})"
    )


def _normalised_section(
    grid: Grid,
    title: str,
    paper_means: Mapping[str, tuple[float, float]] | None,
    paper_tests: Mapping[tuple[str, str], paper.PaperTest],
    rng: np.random.Generator,
    reps: int,
    png: Path,
    note: str = "",
) -> str:
    intro = (
        f"## {title}\n\n{note}Each env's final returns are scaled so that the interquartile "
        "range over all its runs (every DM) maps to [0, 1], then pooled over envs. IQM = "
        "interquartile mean, 95 % CI by stratified bootstrap over runs per env "
        f"({reps} resamples)."
    )
    if not grid.dms:
        return intro + "\n\nNo finished cell yet."
    normalised = iqr_normalise(grid.values)
    header = ["DM", "runs", "mean", "SD", "IQM [95 % CI]"] + (["paper"] if paper_means else [])
    lines = [md_row(header), md_row(["---"] * len(header))]
    iqms = {}
    for dm, rng_dm in zip(grid.dms, rng.spawn(len(grid.dms)), strict=True):
        values = normalised[dm]
        mean, sd = mean_sd(values)
        centre, interval = iqm(values), stratified_bootstrap_ci(values, rng_dm, reps=reps)
        iqms[dm] = (centre, interval)
        row = [
            dm,
            str(int(np.isfinite(values).sum())),
            fmt_num(mean, 3),
            fmt_num(sd, 3),
            f"{fmt_num(centre, 3)} [{fmt_num(interval.low, 3)}, {fmt_num(interval.high, 3)}]",
        ]
        if paper_means:
            cited = paper_means.get(dm)
            row.append(f"{cited[0]:g} ± {cited[1]:g}" if cited else DASH)
        lines.append(md_row(row))
    figures.normalised_returns({dm: normalised[dm].ravel() for dm in grid.dms}, iqms, title, png)
    tests = tests_table(normalised, grid.dms, paper_tests, digits=3)
    return (
        f"{intro}\n\n" + "\n".join(lines) + "\n\nWelch t-tests between DMs, pooled over "
        f"envs:\n\n{tests}\n\n![{title.lower()}]({png.name})"
    )


def _capped_section(results: StudyResults, rng: np.random.Generator, reps: int, root: Path) -> str:
    grid, stand_ins = results.capped_grid()
    if not grid.dms:
        text = (
            "## Capped preference pairs\n\nNo finished capped cells: run the study again with "
            "`--ablation capped` (or `--cap-pairs`) for SPEC §8's ablation (each round keeps at "
            "most as many preference pairs as it asked comparisons, the pairwise DM's count)."
        )
        return text
    note = "Each round kept at most one preference pair per comparison. "
    if stand_ins:
        note += f"{', '.join(stand_ins)}: uncapped cells stand in (they never exceeded the cap). "
    return _normalised_section(
        grid,
        "Capped preference pairs",
        paper.CAPPED_MEANS,
        paper.CAPPED_TESTS,
        rng,
        reps,
        root / CAPPED_PNG,
        note,
    )


def _ablations_section(results: StudyResults) -> str:
    names = results.ablations()
    described = "; ".join(f"`{name}`: {ABLATIONS[name].summary}" for name in ABLATIONS)
    title = "## Ablations"
    if not names:
        return (
            f"{title}\n\nNo finished ablation cells: `groupwise study --ablation NAME …` runs "
            f"every cell once more with one change ({described})."
        )
    described = "; ".join(f"`{name}`: {ABLATIONS[name].summary}" for name in names)
    returns = {c: results.grid(c) for c in (MAIN, *names)}
    pairs = {c: results.grid(c, "final_pairs") for c in (MAIN, *names)}
    envs = _merge_order([returns[c].envs for c in names], returns[MAIN].envs)
    dms = _merge_order([returns[c].dms for c in names], returns[MAIN].dms)
    header = ["env", "DM", "default", *names]
    lines = [md_row(header), md_row(["---"] * len(header))]
    for env in envs:
        for dm in dms:
            if not any(finite_column(returns[c], env, dm).size for c in names):
                continue
            lines.append(md_row([env, dm, *(mean_sd_n(returns[c], env, dm) for c in returns)]))
    pair_header = ["DM", "default", *names]
    pair_lines = [md_row(pair_header), md_row(["---"] * len(pair_header))]
    for dm in dms:
        pair_lines.append(md_row([dm, *(pooled_mean(pairs[c], dm, envs) for c in pairs)]))
    return (
        f"{title}\n\nEach ablation runs the cells once more with one change ({described}). "
        "Final true return per env and DM, mean ± SD over finished seeds (n), beside the "
        "default cells:\n\n" + "\n".join(lines) + "\n\nPreference pairs per finished cell, "
        "mean over the envs above and seeds:\n\n" + "\n".join(pair_lines)
    )


def _merge_order(groups: list[tuple[str, ...]], order: tuple[str, ...]) -> tuple[str, ...]:
    """The names in `groups`, those in `order` first and in its order, the rest as found."""
    found = dict.fromkeys(name for group in groups for name in group)
    return (*(n for n in order if n in found), *(n for n in found if n not in order))


def _missing_section(results: StudyResults) -> str:
    unfinished, not_started = results.unfinished(), results.not_started()
    if not unfinished and not not_started:
        return "## Missing cells\n\nNone: every planned cell has finished."
    lines = ["## Missing cells", ""]
    lines += [
        f"- {r.cell.label}: unfinished, {r.rows} of {r.planned_rows} rows" for r in unfinished
    ]
    lines += [f"- {c.label}: not started" for c in not_started]
    lines += ["", "Run the same `groupwise study` command again to finish them."]
    return "\n".join(lines)


def _in_paper(dm: str) -> bool:
    return any(dm in row for row in paper.TABLE1.values())


def _finite_mean(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(finite.mean()) if finite.size else math.nan


def _nan_safe(values: np.ndarray) -> np.ndarray:
    """Columns with no finite value become 0 instead of warning in `nanmean`."""
    return np.where(np.isfinite(values).any(axis=0), values, 0.0)
