"""How many threads the DTW kernels (`dtw_kernels`) run on.

The kernels run on numba's threading layer, OpenMP where available. numba terminates a
child forked from a process that has used the OpenMP layer, so a process that computes
distances should start its workers with "spawn" or "forkserver". Starting that layer sets
the OpenMP thread count of the whole process, torch's OpenMP runtime included (a process
that had asked torch for one thread found it on every core: two quick GridWorld groupwise
cells side by side on two cores took 108 s each instead of 27 s), so every kernel launch
(`dtw.dtw_matrix`) and every change of the count here restores the OpenMP limits it found
(threadpoolctl).
"""

import contextlib
from collections.abc import Iterator

import numba
from threadpoolctl import threadpool_limits


def set_kernel_threads(n: int) -> int:
    """The kernels this thread launches from now on run on `n` threads (at most numba's
    NUMBA_NUM_THREADS, at least 1); returns the count before.

    A process that shares its cores with other work (the app's worker, whose PPO wants one
    thread) starts with NUMBA_NUM_THREADS = its cores, sets one thread here, and raises the
    count only around a distance matrix it computes while nothing else of its own runs
    (`kernel_threads` in `worker.jobs.prepare`).
    """
    with threadpool_limits(limits=None, user_api="openmp"):  # starting the layer resets it
        before = numba.get_num_threads()
        most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # set at numba's import
        numba.set_num_threads(max(1, min(n, most)))
    return before


@contextlib.contextmanager
def kernel_threads(n: int) -> Iterator[int]:
    """`set_kernel_threads(n)` within the block; yields the count set."""
    before = set_kernel_threads(n)
    try:
        yield numba.get_num_threads()
    finally:
        set_kernel_threads(before)
