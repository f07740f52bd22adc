"""Benchmark: the group-variance suggestions (SPEC §5) at 200 and 1,000 behaviours.

Per pool size: the behaviour tree's candidate groups (levels 1-2, 2-8 leaves, the default
`TreeConfig`) of a clustered random pool, ensemble returns (N, 3); then the time of
`score_group_pairs` (every disjoint candidate pair), of `suggestion_order` for lists of 20, 200
and every pair (refilled lists, as a teacher who keeps asking gets), and of the pairwise
top-100 edges (`top_pairs`). For comparison the first implementation's route to the inter
term, the (N, N) pair-variance matrix between the (G, N) memberships (issue 22). Median of
`--repeats`.

    python -m benchmarks suggestions
    python benchmarks/suggestions.py [--sizes 200 1000] [--repeats 5]
"""

import argparse
import statistics
import sys
import time
from collections.abc import Callable, Sequence

import numpy as np
from scipy.spatial.distance import pdist

from groupwise.behaviour import build_tree, group_candidates
from groupwise.query.groups import (
    GroupCandidate,
    pair_variance_matrix,
    score_group_pairs,
    suggestion_order,
)
from groupwise.query.pairwise import top_pairs


def _median_seconds(fn: Callable[[], object], repeats: int) -> float:
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - start)
    return statistics.median(runs)


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:.1f} ms"


def bench_size(n: int, repeats: int, seed: int) -> dict[str, str]:
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(max(4, n // 20), 4)) * 3
    points = centres[rng.integers(0, len(centres), n)] + rng.normal(size=(n, 4))
    tree = build_tree(pdist(points))
    candidates = [GroupCandidate(c.id, c.leaves) for c in group_candidates(tree)]
    returns = rng.normal(size=(n, 3))
    intra = rng.gamma(2.0, 0.5, size=n)

    scores = score_group_pairs(returns, intra, candidates)
    t_score = _median_seconds(lambda: score_group_pairs(returns, intra, candidates), repeats)
    t_20 = _median_seconds(lambda: suggestion_order(scores, 20, refill=True), repeats)
    t_200 = _median_seconds(lambda: suggestion_order(scores, 200, refill=True), repeats)
    t_all = _median_seconds(lambda: suggestion_order(scores, len(scores), refill=True), repeats)
    membership = np.zeros((len(candidates), n))
    for g, c in enumerate(candidates):
        membership[g, list(c.members)] = 1.0 / len(c.members)
    t_old = _median_seconds(
        lambda: membership @ pair_variance_matrix(returns) @ membership.T, repeats
    )
    t_edges = _median_seconds(lambda: top_pairs(returns, 100), repeats)
    return {
        "N": str(n),
        "candidates G": str(len(candidates)),
        "disjoint pairs P": str(len(scores)),
        "score": _ms(t_score),
        "order, 20": _ms(t_20),
        "order, 200": _ms(t_200),
        "order, all P": _ms(t_all),
        "score + 20": _ms(t_score + t_20),
        "first impl.'s inter alone": _ms(t_old),
        "top-100 edges": _ms(t_edges),
    }


def _table(rows: Sequence[dict[str, str]]) -> str:
    head = list(rows[0])
    lines = ["| " + " | ".join(head) + " |", "|" + "---:|" * len(head)]
    lines += ["| " + " | ".join(row[h] for h in head) + " |" for row in rows]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 1000])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    # argv None (as `python -m benchmarks` calls it) means the defaults, not sys.argv
    args = parser.parse_args([] if argv is None else list(argv))
    rows = [bench_size(n, args.repeats, args.seed) for n in args.sizes]
    print(f"Group-variance suggestions, K = 3, median of {args.repeats}.\n")
    print(_table(rows))


if __name__ == "__main__":
    main(sys.argv[1:])
