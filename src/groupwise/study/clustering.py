"""The clustering study (SPEC §4; the paper's supplement §1), re-run.

Question: which way of grouping behaviours gives groups whose true returns are alike? Per
repetition, N behaviours are sampled (`policy_mix.sample_mixed`: n trajectories from a mix of
policies, `windows` windows each), their DTW distances computed on z-scored [obs; act] steps
(`behaviour.pool_features`, `dtw_matrix`), and three methods each cut them into about
`target_clusters` clusters:

- **HC**: the behaviour tree (`behaviour.build_tree`, complete linkage, 4 linear levels);
  the clusters are the level-2 nodes (padding nodes included, so they partition the leaves)
  with more than one leaf; leaves alone in their level-2 node are outliers. The number of
  clusters is whatever the tree gives (it is not tuned).
- **PCA**: classical multidimensional scaling of the DTW distances to 2-D (PCA of the
  embedding implied by the distances; it is PCA itself when they are Euclidean), then DBSCAN.
- **t-SNE**: scikit-learn's t-SNE on the precomputed distances (squared, as t-SNE's Gaussian
  kernel takes squared distances; random init, perplexity min(30, (N − 1) / 3)), then DBSCAN.

DBSCAN (`sklearn.cluster.DBSCAN` on the embedding's precomputed distances):
``min_samples = 2`` (a cluster needs two behaviours, as HC's "more than one leaf"), noise
points (outliers) dropped. eps is chosen per embedding: DBSCAN is run for
`eps_candidates` values of eps, the quantiles 0.25 % … 50 % of the embedding's pairwise
distances, and the eps whose number of clusters is closest to `target_clusters` is kept
(ties: fewer outliers, then the smaller eps).

Measure: intra-cluster variance of the true return = the mean over clusters of the (population)
variance of the member behaviours' true returns (L-step sums); outliers are not in any
cluster. Methods are compared with paired t-tests over repetitions (`scipy.stats.ttest_rel`).

Statistics here are pure functions of arrays; plotting lives in `clustering_plot.py`.
"""

import dataclasses
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats
from scipy.spatial.distance import pdist, squareform
from sklearn.cluster import DBSCAN
from tqdm.auto import tqdm

from groupwise.behaviour import BehaviourTree, TreeConfig, build_tree, dtw_matrix, pool_features
from groupwise.rl.policy import Policy
from groupwise.study.policy_mix import sample_mixed
from groupwise.types import FloatArray, IntArray

logger = logging.getLogger(__name__)

METHODS: tuple[str, ...] = ("HC", "PCA", "t-SNE")
METHOD_NAMES: dict[str, str] = {
    "HC": "HC (tree level 2, > 1 leaf)",
    "PCA": "PCA (classical MDS) + DBSCAN",
    "t-SNE": "t-SNE + DBSCAN",
}

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
class Clustering:
    """One method's clusters of one repetition's behaviours."""

    labels: IntArray  # (N,) cluster of each behaviour, -1 for an outlier
    eps: float | None  # DBSCAN's eps (None for HC)

    @property
    def clusters(self) -> int:
        return cluster_count(self.labels)

    @property
    def outliers(self) -> int:
        return int((self.labels < 0).sum())


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


def intra_cluster_variance(labels: IntArray, returns: FloatArray) -> float:
    """Mean over clusters of the population variance of their members' returns.

    labels (N,): cluster ids, negative for outliers (left out); returns (N,).
    Clusters with a single member count (variance 0) — none of our methods makes them.
    NaN when there is no cluster.
    """
    labels = np.asarray(labels)
    returns = np.asarray(returns, dtype=np.float64)
    if labels.shape != returns.shape:
        raise ValueError(f"labels {labels.shape} and returns {returns.shape} differ")
    ids = np.unique(labels[labels >= 0])
    if ids.size == 0:
        return float("nan")
    return float(np.mean([returns[labels == c].var() for c in ids]))


def cluster_count(labels: IntArray) -> int:
    """Number of clusters (distinct non-negative labels)."""
    labels = np.asarray(labels)
    return int(np.unique(labels[labels >= 0]).size)


def classical_mds(distances: FloatArray, dims: int = 2) -> FloatArray:
    """(N, dims) classical MDS (Torgerson) embedding of a square distance matrix (N, N).

    Double-centres −D²/2 and keeps the top `dims` eigenvectors scaled by √eigenvalue;
    negative eigenvalues (non-Euclidean distances such as DTW) give zero coordinates.
    """
    d = np.asarray(distances, dtype=np.float64)
    n = d.shape[0]
    centring = np.eye(n) - 1.0 / n
    b = -0.5 * centring @ (d**2) @ centring
    values, vectors = np.linalg.eigh((b + b.T) / 2.0)
    top = np.argsort(values)[::-1][:dims]
    return vectors[:, top] * np.sqrt(np.maximum(values[top], 0.0))


def tsne_embedding(
    distances: FloatArray, rng: np.random.Generator, perplexity: float = 30.0
) -> FloatArray:
    """(N, 2) t-SNE embedding of a square distance matrix (N, N) (module docstring).

    Exact gradients (N is a pool, not a data set) on one thread: scikit-learn's Barnes–Hut
    and OpenMP threads cost ~100× more on a busy 2-core machine for N = 50.
    """
    from sklearn.manifold import TSNE
    from threadpoolctl import threadpool_limits

    d = np.asarray(distances, dtype=np.float64)
    n = d.shape[0]
    tsne = TSNE(
        n_components=2,
        metric="precomputed",
        init="random",
        method="exact",
        perplexity=min(perplexity, (n - 1) / 3.0),
        random_state=int(rng.integers(2**31 - 1)),
    )
    with threadpool_limits(limits=1):
        return np.asarray(tsne.fit_transform(d**2))


def dbscan(distances: FloatArray, eps: float, min_samples: int) -> IntArray:
    """DBSCAN labels (N,) from a square distance matrix (N, N); -1 for noise.

    Core points have at least `min_samples` points (themselves included) within `eps`
    (inclusive); a border point joins the first cluster that reaches it.
    """
    # scikit-learn costs 0.76 ms a call against 0.24 ms for the connected-components DBSCAN
    # it replaced (N = 50, 2 cores): 0.2 s more per repetition, whose sampling alone takes
    # 8.2 s on Hopper; the partitions were identical on 8,000 random inputs.
    model = DBSCAN(eps=eps, min_samples=min_samples, metric="precomputed")
    return np.asarray(model.fit(np.asarray(distances, dtype=np.float64)).labels_, dtype=np.int64)


def dbscan_near_target(
    points: FloatArray, target: int, min_samples: int, candidates: int = 200
) -> Clustering:
    """DBSCAN of points (N, dims) with the eps that gives the cluster count closest to
    `target` (ties: fewer outliers, then smaller eps), among `candidates` quantiles
    (0.25 % … 50 %) of the points' pairwise distances."""
    pairwise = pdist(np.asarray(points, dtype=np.float64))
    square = squareform(pairwise)
    positive = pairwise[pairwise > 0]
    if positive.size == 0:  # every point in one place
        return Clustering(np.zeros(len(points), dtype=np.int64), 0.0)
    grid = np.unique(np.quantile(positive, np.linspace(0.0025, 0.5, candidates)))
    best: tuple[tuple[int, int, float], Clustering] | None = None
    for eps in grid:
        labels = dbscan(square, float(eps), min_samples)
        key = (abs(cluster_count(labels) - target), int((labels < 0).sum()), float(eps))
        if best is None or key < best[0]:
            best = (key, Clustering(labels, float(eps)))
    assert best is not None
    return best[1]


def hc_clusters(tree: BehaviourTree, level: int) -> IntArray:
    """(N,) labels: the index of each behaviour's level-`level` node, -1 for behaviours
    alone in theirs."""
    n = len(tree.leaf_order)
    labels = np.full(n, -1, dtype=np.int64)
    for k, node in enumerate(n for n in tree.at_level(level) if n.size > 1):
        labels[list(node.leaves)] = k
    return labels


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
