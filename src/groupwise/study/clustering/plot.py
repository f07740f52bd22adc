"""The clustering study's figure: a box plot of the intra-cluster variance per method."""

from pathlib import Path

import numpy as np

from groupwise.study.clustering.runner import METHODS, ClusteringStudyResult


def plot_variances(result: ClusteringStudyResult, path: Path) -> None:
    """Write a PNG box plot (one box per method, one dot per repetition) to `path`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = [result.variances[m][np.isfinite(result.variances[m])] for m in METHODS]
    figure, axes = plt.subplots(figsize=(5.0, 3.6), dpi=150)
    try:
        axes.boxplot(data, showmeans=True)
        axes.set_xticks(range(1, len(METHODS) + 1), list(METHODS))
        jitter = np.random.default_rng(0)  # fixed: the figure is reproducible
        for k, values in enumerate(data, start=1):
            x = k + jitter.uniform(-0.08, 0.08, size=len(values))
            axes.scatter(x, values, s=12, alpha=0.6, color="tab:blue", zorder=3)
        axes.set_ylabel("intra-cluster variance of true return")
        cfg = result.config
        axes.set_title(f"{cfg.env}: {cfg.reps} repetitions × {result.behaviours} behaviours")
        figure.tight_layout()
        figure.savefig(path)
    finally:
        plt.close(figure)
