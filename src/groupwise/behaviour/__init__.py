"""The behaviour space (SPEC §4): features, exact DTW distances, linkage, the n-ary tree.

Pure numpy/scipy/numba; no torch, FastAPI or SB3. A round uses it as

    features = pool_features(pool.fragments)         # N x (L_i, D), z-scored over the pool
    window = band_window(0.2, 188)                    # Sakoe–Chiba radius: 38 steps
    distances = dtw_matrix(features, window=window)   # (N (N - 1) / 2,) condensed
    tree = build_tree(distances, TreeConfig())        # levels, leaf order, unique ids
    groups = group_candidates(tree)                   # level 1-2 nodes with 2..8 leaves
    payload = to_json(tree, leaf_extra={i: {"clip": url_i} ...})
"""

from groupwise.behaviour.bands import (
    BANDS,
    assign_levels,
    count_thresholds,
    geometric_thresholds,
    linear_thresholds,
)
from groupwise.behaviour.dtw import band_window, dtw_distance, dtw_matrix, warm_up
from groupwise.behaviour.dtw_threads import kernel_threads, set_kernel_threads
from groupwise.behaviour.features import (
    Standardiser,
    fit_standardiser,
    pool_features,
    raw_sequences,
    step_features,
)
from groupwise.behaviour.linkage import LINKAGE_METHODS, as_condensed, leaf_order, linkage_matrix
from groupwise.behaviour.tree import (
    BehaviourTree,
    TreeConfig,
    TreeNode,
    build_tree,
    group_candidates,
    medoids,
)
from groupwise.behaviour.tree_json import from_json, to_json

__all__ = [
    "BANDS",
    "LINKAGE_METHODS",
    "BehaviourTree",
    "Standardiser",
    "TreeConfig",
    "TreeNode",
    "as_condensed",
    "assign_levels",
    "band_window",
    "build_tree",
    "count_thresholds",
    "dtw_distance",
    "dtw_matrix",
    "fit_standardiser",
    "from_json",
    "geometric_thresholds",
    "group_candidates",
    "kernel_threads",
    "leaf_order",
    "linear_thresholds",
    "linkage_matrix",
    "medoids",
    "pool_features",
    "raw_sequences",
    "set_kernel_threads",
    "step_features",
    "to_json",
    "warm_up",
]
