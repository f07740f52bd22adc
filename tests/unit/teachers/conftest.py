"""Hand-built pools for the decision-maker tests."""

from collections.abc import Sequence

import numpy as np
import pytest

from groupwise.behaviour.pool import BehaviourPool
from groupwise.episodes.fragments import Fragment

LENGTH = 10


def build_pool(
    returns: Sequence[float],
    clusters: Sequence[int] | None = None,
    k: int = 3,
    seed: int = 0,
    step_variance: bool = True,
) -> BehaviourPool:
    """A pool whose behaviour i has true return returns[i] (spread evenly over its steps).

    With `clusters`, behaviour i's observations sit near the corner `clusters[i]` of a
    simplex (tiny noise), so the behaviour tree finds those clusters; without, they are
    random walks. Predicted returns (N, k) and the step variance are random.
    """
    rng = np.random.default_rng(seed)
    n = len(returns)
    dim = max(clusters) + 1 if clusters is not None else 3
    fragments = []
    for i, r in enumerate(returns):
        if clusters is not None:
            obs = np.zeros((LENGTH, dim)) + 0.01 * rng.normal(size=(LENGTH, dim))
            obs[:, clusters[i]] += 10.0
        else:
            obs = rng.normal(size=(LENGTH, dim)).cumsum(axis=0)
        fragments.append(
            Fragment(
                obs=obs.astype(np.float32),
                acts=np.zeros((LENGTH, 1), dtype=np.float32),
                true_rewards=np.full(LENGTH, r / LENGTH),
                episode=i,
                start=0,
                reset_seed=0,
            )
        )
    variance = rng.uniform(0.1, 1.0, size=n) if step_variance else None
    return BehaviourPool(0, tuple(fragments), rng.normal(size=(n, k)), variance)


@pytest.fixture
def make_pool():
    """`build_pool`, as a fixture (test modules cannot import conftest under importlib)."""
    return build_pool
