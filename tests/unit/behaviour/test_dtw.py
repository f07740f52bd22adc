import math
import os
import subprocess
import sys

import numpy as np
import pytest
from dtaidistance import dtw_ndim
from scipy.spatial.distance import squareform

from groupwise.behaviour.dtw import coarsen, dtw_distance, dtw_matrix, warm_up


def reference_dtw(x: np.ndarray, y: np.ndarray, window: int | None = None) -> float:
    """The module docstring's recurrence, cell by cell in plain Python."""
    n, m = len(x), len(y)
    r = [[math.inf] * (m + 1) for _ in range(n + 1)]
    r[0][0] = 0.0
    for i in range(n):
        for j in range(m):
            if window is not None and not (
                -window - max(0, n - m) <= j - i <= window + max(0, m - n)
            ):
                continue
            cost = math.sqrt(sum((a - b) ** 2 for a, b in zip(x[i], y[j], strict=True)))
            r[i + 1][j + 1] = cost + min(r[i][j], r[i][j + 1], r[i + 1][j])
    return r[n][m]


def dtaidistance_dtw(x: np.ndarray, y: np.ndarray, window: int | None = None) -> float:
    # dtaidistance counts the diagonal as window 1: our radius r is its window r + 1
    return dtw_ndim.distance(
        x, y, window=None if window is None else window + 1, inner_dist="euclidean", use_c=True
    )


def random_pool(rng: np.random.Generator, n: int, lengths: list[int], dim: int) -> list[np.ndarray]:
    return [rng.normal(size=(int(rng.choice(lengths)), dim)) for _ in range(n)]


def test_three_sequences_by_hand():
    # 3-4-5 triangles: a and b warp onto each other for free; c is one step at a's end
    a = np.array([[0.0, 0.0], [3.0, 4.0]])
    b = np.array([[0.0, 0.0], [0.0, 0.0], [3.0, 4.0]])
    c = np.array([[3.0, 4.0]])
    # dtw(a, c) = |a0 - c0| + |a1 - c0| = 5 + 0; dtw(b, c) = 5 + 5 + 0
    np.testing.assert_array_equal(dtw_matrix([a, b, c]), [0.0, 5.0, 10.0])
    assert dtw_distance(a, c) == 5.0


def test_window_forbids_the_warp():
    x = np.array([[0.0], [5.0], [0.0], [0.0]])
    y = np.array([[0.0], [0.0], [5.0], [0.0]])
    assert dtw_distance(x, y) == 0.0  # x's peak warps one step right
    assert dtw_distance(x, y, window=1) == 0.0
    assert dtw_distance(x, y, window=0) == 10.0  # lock-step: |5 - 0| + |0 - 5|
    np.testing.assert_array_equal(dtw_matrix([x, y], window=0), [10.0])


@pytest.mark.parametrize("window", [None, 0, 1, 3])
@pytest.mark.parametrize("lengths", [[12], [1, 4, 9, 12]], ids=["equal", "unequal"])
def test_matrix_matches_dtaidistance(window, lengths):
    rng = np.random.default_rng(0)
    seqs = random_pool(rng, 21, lengths, dim=5)
    got = squareform(dtw_matrix(seqs, window=window))
    for i in range(len(seqs)):
        for j in range(i + 1, len(seqs)):
            want = dtaidistance_dtw(seqs[i], seqs[j], window)
            assert got[i, j] == pytest.approx(want, rel=1e-10), (i, j)


@pytest.mark.parametrize("window", [None, 0, 2])
def test_matrix_and_pair_match_the_reference_dp(window):
    rng = np.random.default_rng(1)
    seqs = random_pool(rng, 11, [1, 2, 6, 7], dim=3)
    got = squareform(dtw_matrix(seqs, window=window))
    for i in range(len(seqs)):
        for j in range(i + 1, len(seqs)):
            want = reference_dtw(seqs[i], seqs[j], window)
            assert got[i, j] == pytest.approx(want, rel=1e-10)
            assert dtw_distance(seqs[i], seqs[j], window) == pytest.approx(want, rel=1e-12)


def test_many_lengths_fill_and_pad_the_lanes():
    # 8 lanes per batch: runs of 1, 7, 8 and 19 sequences of one length
    rng = np.random.default_rng(2)
    lengths = [3] * 1 + [5] * 7 + [8] * 8 + [4] * 19
    seqs = [rng.normal(size=(length, 4)) for length in rng.permutation(lengths)]
    got = squareform(dtw_matrix(seqs, window=2))
    for i in range(len(seqs)):
        for j in range(i + 1, len(seqs)):
            assert got[i, j] == pytest.approx(dtaidistance_dtw(seqs[i], seqs[j], 2), rel=1e-10)


def test_symmetric_and_zero_for_identical_sequences():
    rng = np.random.default_rng(3)
    seqs = random_pool(rng, 10, [4, 6], dim=3)
    seqs[7] = seqs[2].copy()
    m = squareform(dtw_matrix(seqs, window=1))
    assert m[2, 7] == 0.0  # exactly: near-zero costs are recomputed from differences
    np.testing.assert_array_equal(np.diag(m), 0.0)
    order = rng.permutation(len(seqs))
    shuffled = squareform(dtw_matrix([seqs[i] for i in order], window=1))
    np.testing.assert_allclose(shuffled, m[np.ix_(order, order)], rtol=1e-12)
    for x, y in [(seqs[0], seqs[1]), (seqs[3], seqs[8])]:
        assert dtw_distance(x, y, window=1) == pytest.approx(dtw_distance(y, x, window=1))


def test_large_offsets_do_not_lose_precision():
    # steps far from the origin: ||x||^2 + ||y||^2 - 2 x.y cancels almost completely
    rng = np.random.default_rng(4)
    base = rng.normal(size=(6, 3)) + 1e4
    seqs = [base + 1e-3 * rng.normal(size=base.shape) for _ in range(4)]
    got = squareform(dtw_matrix(seqs))
    for i in range(4):
        for j in range(i + 1, 4):
            assert got[i, j] == pytest.approx(reference_dtw(seqs[i], seqs[j]), rel=1e-9)


def test_small_pools():
    assert dtw_matrix([]).shape == (0,)
    assert dtw_matrix([np.ones((3, 2))]).shape == (0,)
    np.testing.assert_array_equal(dtw_matrix([np.zeros((2, 1)), np.ones((1, 1))]), [2.0])


@pytest.mark.parametrize(
    ("seqs", "window"),
    [
        ([np.ones((3, 2)), np.ones((3, 3))], None),
        ([np.ones((3, 2)), np.ones((0, 2))], None),
        ([np.ones((3, 2)), np.full((2, 2), np.nan)], None),
        ([np.ones(3), np.ones(3)], None),
        ([np.ones((3, 2)), np.ones((3, 2))], -1),
        ([np.ones((3, 2)), np.ones((3, 2))], 1.5),
    ],
)
def test_invalid_input_raises(seqs, window):
    with pytest.raises(ValueError):
        dtw_matrix(seqs, window=window)


def test_warm_up_reports_seconds():
    assert warm_up() >= 0.0


_THREADS_SCRIPT = """
import numpy as np
import torch
torch.set_num_threads(1)
x = torch.randn(256, 256)
for _ in range(3):
    x = torch.tanh(x @ x / 256)  # starts torch's OpenMP runtime
from groupwise.behaviour.dtw import dtw_matrix
rng = np.random.default_rng(0)
dtw_matrix([rng.normal(size=(30, 5)) for _ in range(40)])
print(torch.get_num_threads())
"""


def test_the_parallel_kernel_leaves_torchs_thread_count_alone():
    # numba's OpenMP layer used to set the process's OpenMP thread count to every core,
    # torch's included; a fresh process, because the layer starts once per process
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS")}
    done = subprocess.run(
        [sys.executable, "-c", _THREADS_SCRIPT], capture_output=True, text=True, env=env, check=True
    )
    assert done.stdout.split()[-1] == "1"


def test_progress_counts_pairs_up_to_all_of_them_and_changes_nothing():
    rng = np.random.default_rng(4)
    seqs = [rng.normal(size=(int(rng.integers(3, 9)), 2)) for _ in range(50)]
    reports: list[tuple[int, int]] = []
    with_progress = dtw_matrix(seqs, progress=lambda done, total: reports.append((done, total)))
    np.testing.assert_array_equal(with_progress, dtw_matrix(seqs))
    total = 50 * 49 // 2
    assert reports[0] == (0, total) and reports[-1] == (total, total)
    done = [d for d, _ in reports]
    assert len(done) >= 3 and done == sorted(set(done))  # about ten launches: increasing


def test_coarsen_by_hand():
    x = np.arange(10.0).reshape(5, 2)  # steps (0, 1), (2, 3), (4, 5), (6, 7), (8, 9)
    np.testing.assert_array_equal(coarsen(x, 2), [[1.0, 2.0], [5.0, 6.0], [8.0, 9.0]])
    np.testing.assert_array_equal(coarsen(x, 5), [[4.0, 5.0]])
    np.testing.assert_array_equal(coarsen(x, 7), [[4.0, 5.0]])
    np.testing.assert_array_equal(coarsen(x, 1), x)
    with pytest.raises(ValueError):
        coarsen(x, 0)


@pytest.mark.parametrize(("window", "stride"), [(None, 2), (None, 3), (4, 2), (0, 3)])
def test_stride_is_the_scaled_distance_of_block_means(window, stride):
    """dtw(x, y; window r, stride s) = s · dtw(coarsen(x), coarsen(y); window ceil(r / s)),
    by the matrix, the pair function and the reference programme alike."""
    rng = np.random.default_rng(4)
    seqs = random_pool(rng, 13, [5, 9, 12], dim=4)
    got = squareform(dtw_matrix(seqs, window=window, stride=stride))
    coarse_window = None if window is None else -(-window // stride)
    for i in range(len(seqs)):
        for j in range(i + 1, len(seqs)):
            a, b = coarsen(seqs[i], stride), coarsen(seqs[j], stride)
            want = stride * reference_dtw(a, b, coarse_window)
            assert got[i, j] == pytest.approx(want, rel=1e-10)
            assert dtw_distance(seqs[i], seqs[j], window, stride) == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("window", [0, 2, 5])
def test_a_band_on_long_equal_windows_matches_dtaidistance(window):
    """The banded kernel computes only the band's products: rows pair up over the union of
    their ranges, which must not leave a cell of either row out."""
    rng = np.random.default_rng(5)
    seqs = random_pool(rng, 17, [40], dim=6)
    got = squareform(dtw_matrix(seqs, window=window))
    for i in range(len(seqs)):
        for j in range(i + 1, len(seqs)):
            want = dtaidistance_dtw(seqs[i], seqs[j], window)
            assert got[i, j] == pytest.approx(want, rel=1e-10)
