"""Two published ways to get more out of few preference labels (issue 41), as `Objective`s.

**Temporal crops** (QPA, Hu et al. ICLR 2024, github.com/huxiao09/QPA `reward_model.py`,
`get_cropping_mask` and `train_reward_iter`; SURF's `get_cropping_mask` is the same idea):
each labelled pair is scored `count` times, each time on a crop of both fragments. Per
crop and pair one length is drawn uniformly from [S − 15, S − 5] of S = 50 steps (35–45,
here `low`·L … `high`·L), and each fragment gets its own uniform start, so the two crops
have the same length but need not be aligned in time. The pair keeps its label; the loss is
the cross-entropy of the cropped sums, averaged over crops and pairs (the full fragments
are not scored besides). QPA draws the crops afresh in every minibatch and per ensemble
member, as here, and uses `data_aug_ratio` 20 crops.

**Confident pseudo-labels** (SURF, Park et al. ICLR 2022, github.com/alinlab/SURF
`reward_model_semi_dataaug.py`, `semi_train_reward`): with every labelled minibatch of b
pairs comes a minibatch of μ·b unlabelled pairs (μ = 1), drawn per member; each member
labels a pair with the side its own uncropped P(a ≻ b) = σ(R(a) − R(b)) favours, and the
pair counts only where that probability's larger side is at least τ (`threshold_u` 0.95);
its loss is the masked cross-entropy (of the crops when cropping), averaged over the
unlabelled minibatch and added with weight λ_u = 1. SURF keeps unlabelled segment pairs
drawn from its replay buffer; here they are pairs of the round's pool (`unlabelled`).
"""

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import torch
from torch import Tensor

from groupwise.reward.network import RewardNet
from groupwise.reward.objective import BradleyTerryLoss, Objective, pair_cross_entropy
from groupwise.types import FloatArray

CROP_SHARE = (0.7, 0.9)
"""Crop lengths as shares of L: QPA's 35–45 steps of 50."""
UNLABELLED_PER_LABELLED = 1.0
"""SURF's μ: unlabelled pairs per labelled pair of a minibatch (its default and configs)."""
UNLABELLED_WEIGHT = 1.0
"""SURF's λ_u: the weight of the pseudo-labelled loss."""

FeatureFn = Callable[[np.ndarray, np.ndarray], Tensor]
"""(obs (..., obs_dim), acts (..., act_dim)) -> the net's raw inputs (..., D)."""


def crop_masks(
    count: int,
    batch: tuple[int, ...],
    length: int,
    share: tuple[float, float],
    rng: np.random.Generator,
) -> np.ndarray:
    """(count, *batch, 2, length) bool: `count` crops of each pair of `batch` (e.g. (K, b)).

    Per crop and pair, one length drawn uniformly from round(share[0]·L) … round(share[1]·L)
    (at least 1, at most L), and for each of the pair's two fragments its own start, so
    both crops of a pair have the same length and each is a contiguous stretch of its own
    fragment.

    Raises:
        ValueError: `count` < 1, `length` < 1 or a share outside (0, 1] or decreasing.
    """
    low, high = share
    if count < 1 or length < 1 or not 0.0 < low <= high <= 1.0:
        raise ValueError(
            f"need count >= 1, length >= 1 and 0 < low <= high <= 1, got {count}, {length}, {share}"
        )
    shortest = min(length, max(1, round(low * length)))
    longest = min(length, max(shortest, round(high * length)))
    sizes = rng.integers(shortest, longest + 1, size=(count, *batch))
    starts = rng.integers(0, length - sizes[..., None] + 1, size=(count, *batch, 2))
    steps = np.arange(length)
    return (steps >= starts[..., None]) & (steps < (starts + sizes[..., None])[..., None])


@dataclass(frozen=True)
class TemporalCrops:
    """The Bradley–Terry loss over `count` temporal crops of each pair (module docstring)."""

    count: int = 20
    share: tuple[float, float] = CROP_SHARE

    def __post_init__(self) -> None:
        crop_masks(self.count, (), 1, self.share, np.random.default_rng(0))  # validates

    def loss(
        self,
        net: RewardNet,
        rewards: Tensor,
        labels: Tensor,
        rng: np.random.Generator,
        weights: Tensor | None = None,
    ) -> Tensor:
        del net
        *batch, _, length = rewards.shape
        masks = crop_masks(self.count, tuple(batch), length, self.share, rng)
        cropped = (rewards.unsqueeze(0) * torch.from_numpy(masks).to(rewards.dtype)).sum(-1)
        return pair_cross_entropy(cropped, labels, weights).mean(dim=(0, 2))  # of (count, K, b)


def confident_labels(p: Tensor, threshold: float) -> tuple[Tensor, Tensor]:
    """SURF's pseudo-labels of pairs whose first side is preferred with probability `p`:
    (labels, mask), each shaped like `p`: label 1.0 where p ≥ ½ and 0.0 below, and mask 1.0
    only where max(p, 1 − p) ≥ `threshold` (a pair the model is that sure about), else 0.0.

    Raises:
        ValueError: `threshold` outside [0.5, 1].
    """
    if not 0.5 <= threshold <= 1.0:
        raise ValueError(f"a confidence threshold is in [0.5, 1], got {threshold}")
    labels = (p >= 0.5).to(p.dtype)
    mask = (torch.maximum(p, 1.0 - p) >= threshold).to(p.dtype)
    return labels, mask


@dataclass(frozen=True, eq=False)
class PseudoLabels:
    """`inner`'s loss on the labelled minibatch plus its loss on confidently pseudo-labelled
    pairs of `unlabelled` fragments (module docstring, SURF).

    `obs` (U, L, obs_dim) and `acts` (U, L, act_dim) are the unlabelled fragments (U ≥ 2),
    the same L as the labelled ones; `features` turns them into the net's raw inputs
    (`RewardEnsemble.features`)."""

    obs: FloatArray
    acts: FloatArray
    features: FeatureFn
    threshold: float = 0.95
    inner: Objective = field(default_factory=BradleyTerryLoss)
    per_labelled: float = UNLABELLED_PER_LABELLED
    weight: float = UNLABELLED_WEIGHT

    def __post_init__(self) -> None:
        if len(self.obs) < 2 or len(self.obs) != len(self.acts):
            raise ValueError(f"need >= 2 unlabelled fragments, got {len(self.obs)}")
        confident_labels(torch.zeros(1), self.threshold)  # validates the threshold

    def loss(
        self,
        net: RewardNet,
        rewards: Tensor,
        labels: Tensor,
        rng: np.random.Generator,
        weights: Tensor | None = None,
    ) -> Tensor:
        labelled = self.inner.loss(net, rewards, labels, rng, weights)
        members, b = rewards.shape[0], rewards.shape[1]
        pairs = _distinct_pairs(len(self.obs), (members, math.ceil(self.per_labelled * b)), rng)
        x = net.norm(self.features(self.obs[pairs], self.acts[pairs]))  # (K, m, 2, L, D)
        u = net.mlp(x.reshape(members, -1, x.shape[-1])).reshape(*pairs.shape, -1)
        with torch.no_grad():
            returns = u.sum(dim=-1)
            p = torch.sigmoid(returns[..., 0] - returns[..., 1])  # (K, m), each member's own
            pseudo, mask = confident_labels(p, self.threshold)
        return labelled + self.weight * self.inner.loss(net, u, pseudo, rng, mask)


def _distinct_pairs(n: int, shape: tuple[int, int], rng: np.random.Generator) -> np.ndarray:
    """(*shape, 2) index pairs into n items, uniform over ordered pairs of two different ones."""
    first = rng.integers(0, n, size=shape)
    second = (first + rng.integers(1, n, size=shape)) % n
    return np.stack([first, second], axis=-1)
