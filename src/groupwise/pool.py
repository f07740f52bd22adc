"""A round's behaviour pool: the fragments on offer and what the ensemble predicts of them.

Behaviour i of a pool is named ``b<i>`` wherever a person or a file sees it (the tree's leaf
ids, the page, the database, exports); `behaviour_id` and `behaviour_index` are the only
places that spell that name.
"""

import functools
from dataclasses import dataclass, field

import numpy as np

from groupwise.fragments import Fragment, Trajectory
from groupwise.types import FloatArray

BEHAVIOUR_PREFIX = "b"


def behaviour_id(index: int) -> str:
    """The name of pool behaviour `index`: ``b<index>``."""
    return f"{BEHAVIOUR_PREFIX}{int(index)}"


def behaviour_index(name: str) -> int:
    """The pool index of behaviour `name` (``b<index>``).

    Raises:
        ValueError: `name` is not a behaviour name.
    """
    digits = name[len(BEHAVIOUR_PREFIX) :]
    if not name.startswith(BEHAVIOUR_PREFIX) or not digits.isdigit():
        raise ValueError(f"{name!r} is not a behaviour id (b<index>)")
    return int(digits)


@dataclass(frozen=True)
class BehaviourPool:
    """The behaviours of one round.

    `predicted_returns` is computed once per round (SPEC §5) and shared by every query
    strategy: row i is behaviour i's predicted return under each ensemble member.
    `step_variance` is each behaviour's ensemble variance of its per-step rewards, averaged
    over its steps (`groupwise.query.groups.step_variance`), the intra term of the
    group-variance score; None when the pool was built without it (group active learning
    then falls back to `groupwise.query.groups.return_variance`). `episodes` are the whole
    episodes the fragments were cut from, when known: what replays them into clips.
    """

    round: int
    fragments: tuple[Fragment, ...]
    predicted_returns: FloatArray  # (N, K)
    step_variance: FloatArray | None = None  # (N,)
    episodes: tuple[Trajectory, ...] = field(default=(), repr=False)

    def __post_init__(self) -> None:
        if self.predicted_returns.shape[0] != len(self.fragments):
            raise ValueError(
                f"{self.predicted_returns.shape[0]} predicted returns for "
                f"{len(self.fragments)} fragments"
            )
        if self.step_variance is not None and self.step_variance.shape != (len(self.fragments),):
            raise ValueError(
                f"step variance of shape {self.step_variance.shape} for "
                f"{len(self.fragments)} fragments"
            )

    def __len__(self) -> int:
        return len(self.fragments)

    @property
    def true_returns(self) -> FloatArray:
        """(N,) true return of each behaviour (for simulated users and evaluation only)."""
        return np.array([f.true_return for f in self.fragments])

    @functools.cached_property
    def distances(self) -> FloatArray:
        """Condensed exact DTW distances of the pool's behaviours (SPEC §4), computed once."""
        from groupwise.behaviour import dtw_matrix, pool_features

        return dtw_matrix(pool_features(self.fragments))
