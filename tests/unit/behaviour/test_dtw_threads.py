import numba
import numpy as np

from groupwise.behaviour.dtw import dtw_matrix
from groupwise.behaviour.dtw_threads import kernel_threads


def test_kernel_threads_set_the_count_within_the_block_and_restore_it():
    rng = np.random.default_rng(3)
    seqs = [rng.normal(size=(int(rng.choice([9, 12])), 3)) for _ in range(24)]
    before = numba.get_num_threads()
    with kernel_threads(1) as threads:
        assert threads == numba.get_num_threads() == 1
        one = dtw_matrix(seqs)
    assert numba.get_num_threads() == before
    with kernel_threads(10**6) as threads:  # clamped to numba's NUMBA_NUM_THREADS
        assert threads == numba.config.NUMBA_NUM_THREADS
        every = dtw_matrix(seqs)
    assert numba.get_num_threads() == before
    np.testing.assert_array_equal(one, every)
