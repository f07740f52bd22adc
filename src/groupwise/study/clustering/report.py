"""The clustering study's result as Markdown (`markdown_table`) and JSON (`to_json`)."""

import dataclasses

import numpy as np

from groupwise.study.clustering.runner import METHODS, ClusteringStudyResult
from groupwise.types import FloatArray, IntArray

METHOD_NAMES: dict[str, str] = {
    "HC": "HC (tree level 2, > 1 leaf)",
    "PCA": "PCA (classical MDS) + DBSCAN",
    "t-SNE": "t-SNE + DBSCAN",
}


def _mean_sd(values: FloatArray | IntArray, digits: int = 3) -> str:
    values = np.asarray(values, dtype=np.float64)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return "—"
    sd = values.std(ddof=1) if values.size > 1 else 0.0
    return f"{values.mean():.{digits}g} ± {sd:.{digits}g}"


def _number(value: float | None, fmt: str) -> str:
    return "—" if value is None or not np.isfinite(value) else format(value, fmt)


def markdown_table(result: ClusteringStudyResult) -> str:
    """The study's Markdown report: per-method mean ± SD and the tests beside the paper's."""
    cfg = result.config
    lines = [
        f"## Clustering study: {cfg.env}",
        "",
        f"{cfg.reps} repetitions × {result.behaviours} behaviours ({cfg.trajectories} "
        f"trajectories × {cfg.windows} window(s) of {cfg.length} steps; policies: "
        f"{', '.join(result.policies)}). Intra-cluster variance of the true return "
        "(mean over clusters of the variance of member returns), mean ± SD over repetitions.",
        "",
        "| method | intra-cluster variance | clusters | outliers |",
        "|---|---:|---:|---:|",
    ]
    names = {
        **METHOD_NAMES,
        "HC": f"HC (tree level {cfg.hc_level} of {cfg.tree.levels}, {cfg.tree.bands} bands, "
        "> 1 leaf)",
    }
    for method in METHODS:
        lines.append(
            f"| {names[method]} | {_mean_sd(result.variances[method])} | "
            f"{_mean_sd(result.clusters[method], 2)} | {_mean_sd(result.outliers[method], 2)} |"
        )
    lines.append(
        f"| (no clustering: all behaviours) | {_mean_sd(result.return_variance)} | 1 | 0 |"
    )
    lines += [
        "",
        "Paired t-tests over repetitions (t > 0: the first method's clusters vary more).",
        "",
        "| test | t | p | t (paper) | p (paper) |",
        "|---|---:|---:|---:|---:|",
    ]
    for test in result.tests:
        lines.append(
            f"| {test.a} vs {test.b} | {_number(test.t, '.2f')} | {_number(test.p, '.4f')} | "
            f"{_number(test.paper_t, '.2f')} | {_number(test.paper_p, '.4f')} |"
        )
    return "\n".join(lines) + "\n"


def to_json(result: ClusteringStudyResult) -> dict[str, object]:
    """The result as JSON-serialisable data (per-repetition values included)."""
    return {
        "config": dataclasses.asdict(result.config),
        "behaviours": result.behaviours,
        "policies": list(result.policies),
        "variances": {m: v.tolist() for m, v in result.variances.items()},
        "clusters": {m: v.tolist() for m, v in result.clusters.items()},
        "outliers": {m: v.tolist() for m, v in result.outliers.items()},
        "return_variance": result.return_variance.tolist(),
        "tests": [dataclasses.asdict(t) for t in result.tests],
    }
