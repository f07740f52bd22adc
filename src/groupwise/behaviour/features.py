"""Per-step feature sequences of a behaviour pool, standardised over the pool (SPEC §4).

A behaviour becomes the sequence of its step vectors [obs_t ; act_t] (actions already
encoded, one-hot for Discrete). Each of the D dimensions is then z-scored over every step
of every behaviour in the pool, so that dimensions with a large scale (a velocity in m/s
next to a joint angle in rad) do not dominate the DTW distance. The prototype measured raw
features and the paper does not say; standardising is our choice (SPEC §4).

A dimension that is constant over the whole pool carries no information: it is mapped to
exactly 0 instead of dividing by a zero standard deviation.
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from groupwise.episodes.fragments import Fragment
from groupwise.types import FloatArray

BehaviourLike = Fragment | npt.ArrayLike
"""A fragment, or an array (L, D) of its step vectors."""


@dataclass(frozen=True)
class Standardiser:
    """Per-dimension z-scoring fitted on one pool.

    Constant dimensions have `scale` 1 and `constant` True; `apply` maps them to 0.
    """

    mean: FloatArray  # (D,)
    scale: FloatArray  # (D,) standard deviation, 1 where the dimension is constant
    constant: npt.NDArray[np.bool_]  # (D,) True where every step of the pool has one value

    def __post_init__(self) -> None:
        d = self.mean.shape
        if self.scale.shape != d or self.constant.shape != d or len(d) != 1:
            raise ValueError(
                f"mean {self.mean.shape}, scale {self.scale.shape} and constant "
                f"{self.constant.shape} must all be (D,)"
            )

    @property
    def dim(self) -> int:
        return int(self.mean.shape[0])

    def apply(self, sequence: FloatArray) -> FloatArray:
        """(L, D) raw steps -> (L, D) float64 standardised steps."""
        seq = np.asarray(sequence, dtype=np.float64)
        if seq.ndim != 2 or seq.shape[1] != self.dim:
            raise ValueError(f"expected a sequence (L, {self.dim}), got {seq.shape}")
        out = (seq - self.mean) / self.scale
        out[:, self.constant] = 0.0
        return out


def step_features(fragment: Fragment) -> FloatArray:
    """(L, obs_dim + act_dim) float64: the step vectors [obs_t ; act_t] of one fragment."""
    obs = np.asarray(fragment.obs, dtype=np.float64)
    acts = np.asarray(fragment.acts, dtype=np.float64)
    if obs.ndim == 1:
        obs = obs[:, None]
    if acts.ndim == 1:
        acts = acts[:, None]
    if obs.shape[0] != acts.shape[0]:
        raise ValueError(f"fragment has {obs.shape[0]} observations but {acts.shape[0]} actions")
    return np.concatenate([obs, acts], axis=1)


def raw_sequences(items: Sequence[BehaviourLike]) -> list[FloatArray]:
    """Step-vector sequences (L_i, D) float64 of fragments or arrays, unstandardised.

    Raises ValueError for an empty pool, an empty or non-finite sequence, or sequences
    that disagree on D.
    """
    if len(items) == 0:
        raise ValueError("the pool has no behaviours")
    sequences = []
    for i, item in enumerate(items):
        if isinstance(item, Fragment):
            seq = step_features(item)
        else:
            seq = np.asarray(item, dtype=np.float64)
        if seq.ndim != 2 or seq.shape[0] == 0:
            raise ValueError(f"behaviour {i}: expected a non-empty array (L, D), got {seq.shape}")
        if not np.isfinite(seq).all():
            raise ValueError(f"behaviour {i} has non-finite values")
        sequences.append(seq)
    dims = {s.shape[1] for s in sequences}
    if len(dims) != 1:
        raise ValueError(f"behaviours disagree on the step dimension: {sorted(dims)}")
    return sequences


def fit_standardiser(sequences: Sequence[FloatArray]) -> Standardiser:
    """Fit mean and standard deviation of each dimension over all steps of all sequences."""
    steps = np.concatenate([np.asarray(s, dtype=np.float64) for s in sequences], axis=0)
    constant = steps.max(axis=0) == steps.min(axis=0)
    mean = steps.mean(axis=0)
    std = steps.std(axis=0)
    # a non-constant dimension with a std that rounds to 0 would blow up; treat it as constant
    constant |= ~(std > 0.0)
    scale = np.where(constant, 1.0, std)
    return Standardiser(mean=mean, scale=scale, constant=constant)


def pool_features(items: Sequence[BehaviourLike]) -> list[FloatArray]:
    """The standardised step sequences of one pool, in pool order.

    items: N fragments or arrays (L_i, D); lengths may differ.
    Returns N float64 arrays (L_i, D), each dimension z-scored over all steps of the pool.
    """
    sequences = raw_sequences(items)
    standardiser = fit_standardiser(sequences)
    return [standardiser.apply(s) for s in sequences]
