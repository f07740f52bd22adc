"""What a Bradley–Terry fit minimises per minibatch: the part of `bradley_terry.fit` a remedy
may replace (issue 41), as imitation lets a reward trainer take a loss object.

    loss = objective.loss(net, rewards, labels, rng)      # (K,) one value per member

`rewards` are the members' per-step rewards of the minibatch's pairs, (K, b, 2, L), with
gradients; `labels` (K, b) the probability that each pair's first fragment is preferred.
The default, `BradleyTerryLoss`, is SPEC §3's cross-entropy of σ(R(a) − R(b)) with R the
sum over the fragment; `reward.augment` holds the published variants (temporal crops,
confident pseudo-labels), and `reward.round_fit.objective_of` builds the one a
`RewardConfig` asks for.
"""

from typing import Protocol

import numpy as np
from torch import Tensor
from torch.nn.functional import binary_cross_entropy_with_logits

from groupwise.reward.network import RewardNet


class Objective(Protocol):
    """Each member's training loss on one minibatch."""

    def loss(
        self,
        net: RewardNet,
        rewards: Tensor,
        labels: Tensor,
        rng: np.random.Generator,
        weights: Tensor | None = None,
    ) -> Tensor:
        """(K,) the members' mean loss over the b pairs, each pair's loss times its weight
        in `weights` (K, b) when given. `net` scores inputs outside the minibatch (an
        objective with unlabelled pairs); `rng` draws what the objective draws (crops)."""
        ...


class BradleyTerryLoss:
    """SPEC §3: binary cross-entropy of σ(R(a) − R(b)) against the label, R the sum of the
    fragment's per-step rewards."""

    def loss(
        self,
        net: RewardNet,
        rewards: Tensor,
        labels: Tensor,
        rng: np.random.Generator,
        weights: Tensor | None = None,
    ) -> Tensor:
        del net, rng  # nothing outside the minibatch, nothing drawn
        return pair_cross_entropy(rewards.sum(dim=-1), labels, weights).mean(dim=1)


def pair_cross_entropy(returns: Tensor, labels: Tensor, weights: Tensor | None) -> Tensor:
    """Each pair's cross-entropy of σ(R(a) − R(b)) against its label, times its weight when
    `weights` is given: `returns` (…, 2) the pairs' two returns, `labels` and `weights`
    broadcast to their shape (…)."""
    logits = returns[..., 0] - returns[..., 1]
    ce = binary_cross_entropy_with_logits(logits, labels.expand_as(logits), reduction="none")
    return ce if weights is None else ce * weights
