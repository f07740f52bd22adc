"""A round's behaviour pool: the fragments on offer and what the ensemble predicts of them."""

from dataclasses import dataclass

import numpy as np

from groupwise.fragments import Fragment
from groupwise.types import FloatArray


@dataclass(frozen=True)
class BehaviourPool:
    """The behaviours of one round.

    `predicted_returns` is computed once per round (SPEC §5) and shared by every query
    strategy: row i is behaviour i's predicted return under each ensemble member.
    `step_variance` is each behaviour's ensemble variance of its per-step rewards, averaged
    over its steps (`groupwise.query.groups.step_variance`), the intra term of the
    group-variance score; None when the pool was built without it (group active learning
    then falls back to `groupwise.query.groups.return_variance`).
    """

    round: int
    fragments: tuple[Fragment, ...]
    predicted_returns: FloatArray  # (N, K)
    step_variance: FloatArray | None = None  # (N,)

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
