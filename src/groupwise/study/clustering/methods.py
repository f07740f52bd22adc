"""How the clustering study cuts behaviours into clusters, and how it scores a cut
(SPEC §4; the paper's supplement §1). Pure functions of arrays; `clustering_runner` runs
the study with them.

Each method cuts N behaviours, given their DTW distances, into about `target_clusters`
clusters:

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

Score: intra-cluster variance of the true return = the mean over clusters of the
(population) variance of the member behaviours' true returns (L-step sums); outliers are
not in any cluster.
"""

from dataclasses import dataclass

import numpy as np
from scipy.spatial.distance import pdist, squareform
from sklearn.cluster import DBSCAN

from groupwise.behaviour import BehaviourTree
from groupwise.types import FloatArray, IntArray


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
