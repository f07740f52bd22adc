"""The clustering study (SPEC §4; the paper's supplement §1), re-run.

Question: which way of grouping behaviours gives groups whose true returns are alike? Per
repetition, N behaviours are sampled (`policy_mix.sample_mixed`: n trajectories from a mix of
policies, `windows` windows each), their DTW distances computed on z-scored [obs; act] steps
(`behaviour.pool_features`, `dtw_matrix`), and the three methods of `clustering_methods`
(HC, PCA + DBSCAN, t-SNE + DBSCAN) each cut them into about `target_clusters` clusters,
scored by the intra-cluster variance of the true return. Methods are compared with paired
t-tests over repetitions (`scipy.stats.ttest_rel`).

`clustering_report` writes the result as Markdown and JSON; `clustering_plot` draws it.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats
from scipy.spatial.distance import squareform
from tqdm.auto import tqdm

from groupwise.behaviour import TreeConfig, build_tree, dtw_matrix, pool_features
from groupwise.rl.policy import Policy
from groupwise.study.clustering.methods import (
    Clustering,
    classical_mds,
    dbscan_near_target,
    hc_clusters,
    intra_cluster_variance,
    tsne_embedding,
)
from groupwise.study.clustering.policy_mix import sample_mixed
from groupwise.types import FloatArray, IntArray

METHODS: tuple[str, ...] = ("HC", "PCA", "t-SNE")

PAPER_TESTS: dict[tuple[str, str], tuple[float, float]] = {
    ("PCA", "HC"): (6.54, 0.0001),
    ("t-SNE", "HC"): (4.47, 0.0016),
    ("PCA", "t-SNE"): (-0.46, 0.66),
}
"""(a, b) → the paper's (t, p) of the paired t-test of a's variances against b's; t > 0 means
a's groups vary more. The paper writes the first two as "HC < PCA" and "HC < t-SNE"."""


@dataclass(frozen=True)
class ClusteringStudyConfig:
    """One clustering study."""

    env: str = "Hopper"
    """Env with a true reward (short name or Gymnasium id)."""
    reps: int = 10
    """Repetitions (the paper: 10)."""
    trajectories: int = 50
    """Trajectories per repetition, n (the paper: 50)."""
    windows: int = 1
    """Windows of L steps taken from each trajectory: N = trajectories × windows."""
    length: int = 30
    """Steps per behaviour, L."""
    target_clusters: int = 10
    """Clusters DBSCAN's eps is tuned for (the paper: "about 10")."""
    min_samples: int = 2
    """DBSCAN's min_samples."""
    eps_candidates: int = 200
    """Values of eps tried per embedding."""
    perplexity: float = 30.0
    """t-SNE perplexity (lowered to (N − 1) / 3 for small N)."""
    tree: TreeConfig = field(default_factory=TreeConfig)
    """How the HC tree is cut."""
    hc_level: int = 2
    """Tree level whose nodes are HC's clusters."""
    biased_policies: int = 4
    """Biased random policies mixed with the random one when no checkpoints are given."""
    bias_scale: float = 0.5
    """Strength of their bias (see `policy_mix`)."""
    checkpoints: tuple[str, ...] = ()
    """Checkpoint directories of partly trained policies mixed with the random one."""

    def __post_init__(self) -> None:
        if self.reps < 2:
            raise ValueError(f"a paired t-test needs >= 2 repetitions, got {self.reps}")
        if self.trajectories * self.windows < 4:
            raise ValueError("need at least 4 behaviours per repetition")
        if not 1 <= self.hc_level < self.tree.levels:
            raise ValueError(f"hc_level must be in 1 … {self.tree.levels - 1}")


@dataclass(frozen=True)
class PairedTest:
    """Paired t-test of method a's per-repetition variances against method b's."""

    a: str
    b: str
    t: float  # > 0: a's clusters vary more than b's
    p: float  # two-sided
    paper_t: float | None
    paper_p: float | None


@dataclass(frozen=True)
class ClusteringStudyResult:
    """Per-repetition results, {method: array (reps,)}, and the tests between methods."""

    config: ClusteringStudyConfig
    behaviours: int  # N per repetition
    policies: tuple[str, ...]
    variances: dict[str, FloatArray]  # method -> (reps,) intra-cluster variance of the return
    clusters: dict[str, IntArray]  # method -> (reps,)
    outliers: dict[str, IntArray]  # method -> (reps,)
    return_variance: FloatArray  # (reps,) variance of the return over all behaviours
    tests: tuple[PairedTest, ...]


def cluster_behaviours(
    condensed: FloatArray, cfg: ClusteringStudyConfig, rng: np.random.Generator
) -> dict[str, Clustering]:
    """Every method's clusters of one repetition, from its condensed DTW distances."""
    square = squareform(condensed)
    tree = build_tree(condensed, cfg.tree)
    pca = classical_mds(square)
    tsne = tsne_embedding(square, rng, cfg.perplexity)
    return {
        "HC": Clustering(hc_clusters(tree, cfg.hc_level), None),
        "PCA": dbscan_near_target(pca, cfg.target_clusters, cfg.min_samples, cfg.eps_candidates),
        "t-SNE": dbscan_near_target(tsne, cfg.target_clusters, cfg.min_samples, cfg.eps_candidates),
    }


def paired_tests(
    variances: Mapping[str, FloatArray],
    pairs: Sequence[tuple[str, str]] = tuple(PAPER_TESTS),
) -> tuple[PairedTest, ...]:
    """Paired t-tests (a against b) over repetitions; repetitions where either is NaN are
    left out."""
    out = []
    for a, b in pairs:
        result = stats.ttest_rel(variances[a], variances[b], nan_policy="omit")
        paper = PAPER_TESTS.get((a, b))
        out.append(
            PairedTest(
                a=a,
                b=b,
                t=float(result.statistic),
                p=float(result.pvalue),
                paper_t=paper[0] if paper else None,
                paper_p=paper[1] if paper else None,
            )
        )
    return tuple(out)


def run_clustering_study(
    cfg: ClusteringStudyConfig,
    policies: Sequence[tuple[str, Policy]],
    rng: np.random.Generator,
    show_progress: bool = True,
) -> ClusteringStudyResult:
    """Run every repetition (module docstring); repetition r uses the r-th child of `rng`."""
    variances: dict[str, list[float]] = {m: [] for m in METHODS}
    clusters: dict[str, list[int]] = {m: [] for m in METHODS}
    outliers: dict[str, list[int]] = {m: [] for m in METHODS}
    spread = []
    behaviours = cfg.trajectories * cfg.windows
    for rep_rng in tqdm(rng.spawn(cfg.reps), desc="repetitions", disable=not show_progress):
        fragments, _ = sample_mixed(
            cfg.env, policies, cfg.trajectories, cfg.windows, cfg.length, rep_rng
        )
        returns = np.array([f.true_return for f in fragments])
        condensed = dtw_matrix(pool_features(fragments))
        for method, clustering in cluster_behaviours(condensed, cfg, rep_rng).items():
            variances[method].append(intra_cluster_variance(clustering.labels, returns))
            clusters[method].append(clustering.clusters)
            outliers[method].append(clustering.outliers)
        spread.append(float(returns.var()))
    as_arrays = {m: np.array(v) for m, v in variances.items()}
    return ClusteringStudyResult(
        config=cfg,
        behaviours=behaviours,
        policies=tuple(name for name, _ in policies),
        variances=as_arrays,
        clusters={m: np.array(v) for m, v in clusters.items()},
        outliers={m: np.array(v) for m, v in outliers.items()},
        return_variance=np.array(spread),
        tests=paired_tests(as_arrays),
    )
