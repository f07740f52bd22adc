"""Clustering-study statistics on hand-made inputs, and a tiny end-to-end run."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.distance import pdist, squareform

from groupwise.behaviour import TreeConfig, build_tree
from groupwise.study.clustering.methods import (
    classical_mds,
    cluster_count,
    dbscan,
    dbscan_near_target,
    hc_clusters,
    intra_cluster_variance,
)
from groupwise.study.clustering.report import markdown_table
from groupwise.study.clustering.runner import (
    METHODS,
    ClusteringStudyConfig,
    ClusteringStudyResult,
    paired_tests,
)


def test_intra_cluster_variance_is_the_mean_of_per_cluster_variances() -> None:
    labels = np.array([0, 0, 1, 1, 1, -1])
    returns = np.array([1.0, 3.0, 0.0, 3.0, 6.0, 100.0])
    # cluster 0: var(1, 3) = 1; cluster 1: var(0, 3, 6) = 6; the outlier is left out
    assert intra_cluster_variance(labels, returns) == pytest.approx((1.0 + 6.0) / 2)


def test_intra_cluster_variance_without_clusters_is_nan() -> None:
    assert np.isnan(intra_cluster_variance(np.array([-1, -1]), np.array([1.0, 2.0])))
    with pytest.raises(ValueError, match="differ"):
        intra_cluster_variance(np.array([0, 0]), np.array([1.0]))


def test_cluster_count_ignores_outliers() -> None:
    assert cluster_count(np.array([3, 3, 7, -1, -1, 0])) == 3
    assert cluster_count(np.array([-1])) == 0


def test_classical_mds_recovers_euclidean_distances() -> None:
    points = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 4.0], [1.0, 1.0]])
    embedding = classical_mds(squareform(pdist(points)))
    np.testing.assert_allclose(pdist(embedding), pdist(points), atol=1e-9)


def _two_blobs_and_a_loner() -> np.ndarray:
    return np.array([[0.0, 0.0], [0.1, 0.0], [0.0, 0.1], [5.0, 5.0], [5.1, 5.0], [20.0, 0.0]])


def test_dbscan_finds_the_blobs_and_marks_the_loner_as_noise() -> None:
    labels = dbscan(squareform(pdist(_two_blobs_and_a_loner())), eps=0.5, min_samples=2)
    np.testing.assert_array_equal(labels, [0, 0, 0, 1, 1, -1])


def test_dbscan_border_points_join_a_cluster_but_do_not_extend_it() -> None:
    # a line 0, 1, 2, 3: with eps 1 and min_samples 3 only 1 and 2 are core
    distances = squareform(pdist(np.arange(4.0)[:, None]))
    np.testing.assert_array_equal(dbscan(distances, 1.0, 3), [0, 0, 0, 0])
    np.testing.assert_array_equal(dbscan(distances, 0.5, 2), [-1, -1, -1, -1])


def test_eps_is_chosen_for_the_target_cluster_count() -> None:
    rng = np.random.default_rng(0)
    centres = np.arange(10)[:, None] * np.array([10.0, 0.0])
    points = np.concatenate([c + rng.normal(0, 0.2, size=(5, 2)) for c in centres])
    clustering = dbscan_near_target(points, target=10, min_samples=2)
    assert clustering.clusters == 10 and clustering.outliers == 0
    assert clustering.eps is not None and clustering.eps < 10
    fewer = dbscan_near_target(points, target=2, min_samples=2)
    assert fewer.clusters < 10


def test_hc_clusters_are_level_nodes_with_more_than_one_leaf() -> None:
    # root height 100, bands 25 / 50 / 75 / 100: the pairs merge at level 1, the pairs
    # with each other at 31 (level 2); the loner only joins at the root
    points = np.array([0.0, 1.0, 30.0, 31.0, 100.0])[:, None]
    tree = build_tree(pdist(points), TreeConfig(levels=4))
    np.testing.assert_array_equal(hc_clusters(tree, level=2), [0, 0, 0, 0, -1])
    labels = hc_clusters(tree, level=1)
    assert labels[4] == -1 and labels[0] == labels[1] != labels[2] == labels[3]


def test_hc_clusters_partition_like_the_tree_level() -> None:
    rng = np.random.default_rng(3)
    tree = build_tree(pdist(rng.normal(size=(40, 3))), TreeConfig(levels=4))
    labels = hc_clusters(tree, level=2)
    for node in tree.at_level(2):
        members = labels[list(node.leaves)]
        if node.size == 1:
            assert members[0] == -1
        else:
            assert len(set(members)) == 1 and members[0] >= 0
    assert cluster_count(labels) == sum(node.size > 1 for node in tree.at_level(2))


def test_paired_tests_match_scipy_and_carry_the_papers_values() -> None:
    variances = {
        "HC": np.array([1.0, 1.2, 0.9, 1.1]),
        "PCA": np.array([2.0, 2.5, 1.9, 2.4]),
        "t-SNE": np.array([2.1, 2.3, 2.0, 2.6]),
    }
    tests = {(t.a, t.b): t for t in paired_tests(variances)}
    diff = variances["PCA"] - variances["HC"]
    expected_t = diff.mean() / (diff.std(ddof=1) / np.sqrt(len(diff)))
    assert tests[("PCA", "HC")].t == pytest.approx(expected_t)
    assert tests[("PCA", "HC")].p < 0.01
    assert (tests[("PCA", "HC")].paper_t, tests[("PCA", "HC")].paper_p) == (6.54, 0.0001)
    assert tests[("PCA", "t-SNE")].paper_t == -0.46


def _result() -> ClusteringStudyResult:
    variances = {
        "HC": np.array([1.0, 2.0]),
        "PCA": np.array([3.0, 5.0]),
        "t-SNE": np.array([4.0, 4.5]),
    }
    return ClusteringStudyResult(
        config=ClusteringStudyConfig(env="GridWorld", reps=2, trajectories=10),
        behaviours=10,
        policies=("random",),
        variances=variances,
        clusters={m: np.array([10, 9]) for m in METHODS},
        outliers={m: np.array([1, 2]) for m in METHODS},
        return_variance=np.array([8.0, 9.0]),
        tests=paired_tests(variances),
    )


def test_table_lists_methods_and_the_papers_numbers() -> None:
    table = markdown_table(_result())
    assert "| HC (tree level 2 of 4, counts bands, > 1 leaf) | 1.5 ± 0.707 |" in table
    assert "6.54" in table and "0.0001" in table and "4.47" in table and "-0.46" in table
    assert table.count("\n| ") >= 8


def test_a_tiny_study_writes_the_table_and_the_figure(tmp_path: Path) -> None:
    from groupwise.cli import main

    code = main(
        ["clustering-study", "--env", "GridWorld", "--reps", "2", "--n", "10",
         "--seed", "1", "--out", str(tmp_path), "-q"]
    )  # fmt: skip
    assert code == 0
    table = (tmp_path / "clustering.md").read_text()
    assert "t-SNE + DBSCAN" in table and "PCA vs HC" in table
    png = (tmp_path / "clustering.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 5000
    assert (tmp_path / "clustering.json").is_file()


def test_the_hc_level_is_an_option(tmp_path: Path) -> None:
    from groupwise.cli import main

    code = main(
        ["clustering-study", "--env", "GridWorld", "--reps", "2", "--n", "10", "--bands",
         "counts", "--hc-level", "1", "--out", str(tmp_path), "-q"]
    )  # fmt: skip
    assert code == 0
    assert "HC (tree level 1 of 4, counts bands" in (tmp_path / "clustering.md").read_text()
    assert main(["clustering-study", "--env", "GridWorld", "--hc-level", "4",
                 "--out", str(tmp_path), "-q"]) == 2  # fmt: skip
