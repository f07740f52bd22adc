"""Benchmark: the full DTW distance matrix of a behaviour pool (SPEC §4).

Compares `groupwise.behaviour.dtw_matrix` (exact, numba) with dtaidistance's C
`dtw_ndim.distance_matrix` (exact, same definition: inner_dist="euclidean") and with
FastDTW (approximate, radius 1, scipy's Euclidean step distance: the prototype's method).
Random pools of N behaviours, L steps, D dimensions. Ours: median (and min) of `--repeats`
runs after a warm-up; the JIT is timed apart, both cold (empty numba cache, in a
subprocess) and warm (first call of a process that finds the cache). FastDTW is timed on a
sample of pairs and extrapolated to all N (N - 1) / 2; so is dtaidistance when
`--dtai-max` is below N.

    python benchmarks/dtw.py [--sizes 200 1000] [--length 30] [--dim 23] [--repeats 5]
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence

import numpy as np

from groupwise.behaviour.dtw import dtw_matrix, warm_up

_JIT_PROBE = "from groupwise.behaviour.dtw import warm_up; print(warm_up())"


def _seconds(fn: Callable[[], object]) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def _jit_seconds(cache_dir: str | None) -> float:
    """warm_up() in a fresh interpreter; cache_dir None uses numba's usual cache."""
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    out = subprocess.run(
        [sys.executable, "-c", _JIT_PROBE], env=env, check=True, capture_output=True, text=True
    )
    return float(out.stdout.strip().splitlines()[-1])


def _pairs(n: int, count: int, rng: np.random.Generator) -> list[tuple[int, int]]:
    i = rng.integers(0, n, size=count)
    j = (i + rng.integers(1, n, size=count)) % n
    return list(zip(i.tolist(), j.tolist(), strict=True))


def _condensed_index(n: int, i: int, j: int) -> int:
    i, j = min(i, j), max(i, j)
    return n * i - i * (i + 1) // 2 + j - i - 1


def _fmt(seconds: float) -> str:
    return f"{seconds * 1e3:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"


def bench_size(
    n: int, length: int, dim: int, repeats: int, dtai_max: int, fastdtw_pairs: int, seed: int
) -> dict[str, str]:
    from dtaidistance import dtw_ndim
    from fastdtw import fastdtw
    from scipy.spatial.distance import euclidean

    rng = np.random.default_rng(seed)
    pool = [rng.normal(size=(length, dim)) for _ in range(n)]
    n_pairs = n * (n - 1) // 2

    ours = dtw_matrix(pool)
    runs = [_seconds(lambda: dtw_matrix(pool)) for _ in range(repeats)]
    t_ours = statistics.median(runs)

    sub = pool[: min(n, dtai_max)]
    m = len(sub)
    start = time.perf_counter()
    dtai = np.asarray(
        dtw_ndim.distance_matrix(sub, inner_dist="euclidean", use_c=True, compact=True)
    )
    t_dtai = (time.perf_counter() - start) * n_pairs / (m * (m - 1) // 2)
    ours_sub = ours if m == n else dtw_matrix(sub)
    dtai_diff = float(np.max(np.abs(dtai - ours_sub) / ours_sub))

    pairs = _pairs(n, fastdtw_pairs, rng)
    start = time.perf_counter()
    approx = [fastdtw(pool[i], pool[j], dist=euclidean)[0] for i, j in pairs]
    t_fast = (time.perf_counter() - start) * n_pairs / len(pairs)
    exact = np.array([ours[_condensed_index(n, i, j)] for i, j in pairs])
    fast_err = float(np.max((np.array(approx) - exact) / exact))

    return {
        "N": str(n),
        "pairs": str(n_pairs),
        "ours (median)": _fmt(t_ours),
        "ours (min)": _fmt(min(runs)),
        "dtaidistance": _fmt(t_dtai) + ("" if m == n else f" (from N = {m})"),
        "FastDTW": _fmt(t_fast) + f" (from {len(pairs)} pairs)",
        "dtai / ours": f"{t_dtai / t_ours:.1f}x",
        "FastDTW / ours": f"{t_fast / t_ours:.0f}x",
        "max rel. diff dtai": f"{dtai_diff:.1e}",
        "FastDTW max rel. excess": f"{fast_err:.1e}",
    }


def _table(rows: Sequence[dict[str, str]]) -> str:
    head = list(rows[0])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(row[h] for h in head) + " |" for row in rows]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 1000])
    parser.add_argument("--length", type=int, default=30, help="L, steps per behaviour")
    parser.add_argument("--dim", type=int, default=23, help="D, obs + act dimensions")
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--dtai-max", type=int, default=1000, help="largest N run in full")
    parser.add_argument("--fastdtw-pairs", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    # argv None (as `python -m benchmarks` calls it) means the defaults, not sys.argv
    args = parser.parse_args([] if argv is None else list(argv))

    with tempfile.TemporaryDirectory() as empty_cache:
        cold = _jit_seconds(empty_cache)
    _jit_seconds(None)  # fill the usual cache if it was empty
    cached = _jit_seconds(None)
    warm_up()
    rows = [
        bench_size(
            n, args.length, args.dim, args.repeats, args.dtai_max, args.fastdtw_pairs, args.seed
        )
        for n in args.sizes
    ]
    print(f"DTW distance matrix, L = {args.length}, D = {args.dim}, random pools, ", end="")
    print(f"{os.cpu_count()} CPUs; ours: median of {args.repeats}, JIT excluded.\n")
    print(_table(rows))
    print(f"\nJIT: cold compile {cold:.1f} s (empty cache); cached first call {cached:.2f} s.")


if __name__ == "__main__":
    main(sys.argv[1:])
