"""Bradley–Terry training of the reward ensemble on preference pairs (SPEC §3).

P(a ≻ b) = σ(R(a) − R(b)) with R the sum of per-step rewards over a fragment, trained by
cross-entropy against labels in {0, 0.5, 1} (0.5 = equal, which pulls R(a) and R(b) together).
Following Christiano et al. 2017 (§2.2.3, "Deep RL from Human Preferences"):

- each member trains on its own bootstrap resample of the training pairs;
- an L2 penalty whose weight is adapted so the validation loss stays between
  `l2_bounds[0]` and `l2_bounds[1]` times the training loss: after every epoch the weight is
  multiplied by `l2_factor` when the ratio is above the band and divided by it when below,
  within `l2_range`. Without that ceiling (and with a factor of 1.5), 30 round-0 epochs on
  an 8-pair validation split raised the weight until every ReLU died: 3 of 8 simulated
  400-pair sessions ended with a constant reward. With the ceiling of 0.1, or a factor of
  1.2, none did; the defaults use both.

All K members train at once (their weights are stacked, see `network`): minibatch s of every
member is one batched forward/backward pass. The members' losses are summed, and as no
parameter is shared, each member's gradient is exactly that of its own loss. AdamW's
decoupled weight decay is off: the adaptive L2 term in the loss is the only regulariser.

The validation split is fixed per pair *index* (a golden-ratio sequence), not redrawn with
the rng each fit: the ensemble is warm-started round after round on the growing, append-only
dataset, so a pair trained on in one round must not be validated on in the next.
"""

import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor
from torch.nn.functional import binary_cross_entropy_with_logits

from groupwise.config import RewardConfig
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward.ensemble import RewardEnsemble
from groupwise.types import IntArray

log = logging.getLogger(__name__)

_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
_TINY = 1e-20
"""Magnitudes below this are flushed to zero (see `_flush_denormals`)."""
_FLUSH_EVERY = 10
"""Gradient steps between flushes: a value needs hundreds of steps (Adam's first moment
decays by 0.9 a step) to fall from `_TINY` to the subnormal range below 1.2e-38."""


@dataclass(frozen=True)
class FitReport:
    """What one `fit` did, measured after its last epoch.

    Losses are the members' mean Bradley–Terry cross-entropy (without the L2 term) on the
    un-resampled pairs; accuracies are the share of non-tie pairs whose labelled side the
    ensemble-mean return difference favours (nan when there are no such pairs).
    """

    loss: float
    """Training cross-entropy (nan for an empty dataset)."""
    accuracy: float
    """Training accuracy over non-tie pairs."""
    validation_accuracy: float
    """Held-out accuracy over non-tie pairs; nan without a validation split."""
    validation_loss: float
    """Held-out cross-entropy; nan without a validation split."""
    l2_weight: float
    """The adaptive L2 coefficient after this fit (carried to the next one)."""
    n_pairs: int
    """All pairs in the dataset (training plus validation)."""
    n_validation: int
    """Pairs held out for validation (0 without a split)."""
    epochs: int
    """Epochs trained."""
    steps: int
    """Gradient steps taken (each one updates every member)."""
    seconds: float
    """Wall time of the whole fit."""


def validation_mask(n_pairs: int, cfg: RewardConfig) -> np.ndarray:
    """(n_pairs,) bool: which pairs are held out for validation.

    Pair i is held out when frac((i + 1)·φ) < `validation_fraction`, φ the golden ratio
    conjugate: about that share of any prefix of the dataset, and the same pairs every
    round. All False below `min_pairs_for_validation` pairs, or when the rule would leave no
    pair on either side.
    """
    if n_pairs < max(cfg.min_pairs_for_validation, 2):
        return np.zeros(n_pairs, dtype=bool)
    mask = np.mod(np.arange(1, n_pairs + 1) * _GOLDEN, 1.0) < cfg.validation_fraction
    if mask.all() or not mask.any():
        return np.zeros(n_pairs, dtype=bool)
    return mask


def fit(
    ensemble: RewardEnsemble,
    dataset: PreferenceDataset,
    cfg: RewardConfig,
    rng: np.random.Generator,
    epochs: int,
) -> FitReport:
    """Train `ensemble` in place on `dataset` for `epochs` epochs and report how it went.

    The input normaliser is first reset to the statistics of the dataset's fragments (the
    dataset is cumulative, so these are the statistics of every fragment trained on so far,
    each counted once). An epoch is one pass of each member over its bootstrap resample, in
    minibatches of `cfg.batch_size` pairs. All randomness (resamples, shuffles) comes from
    `rng`: the same rng state and inputs give identical weights (on one machine and torch
    thread count). Ties (label 0.5) count in the loss and not in the accuracy.

    An empty dataset trains nothing and reports nan losses and accuracies. Gradient steps
    are not capped: an epoch is ceil(0.8·P / batch_size) steps of about 1.5 ms on one CPU
    thread, so 3 epochs over 1,200 pairs take about 1.5 s. (The first fit in a process also
    pays ~1.4 s for torch's one-time `torch._dynamo` import when the optimiser is built.)

    Raises ValueError when the dataset's dims differ from the ensemble's, a label lies
    outside [0, 1], or `epochs` < 0.
    """
    start = time.perf_counter()
    _check(ensemble, dataset, cfg, epochs)
    if not cfg.warm_start and len(dataset):
        ensemble.reinitialise(rng)
    if dataset.n_fragments:
        ensemble.refit_normalizer(dataset.obs, dataset.acts)
    n_pairs = len(dataset)
    if n_pairs == 0:
        log.info("no preference pairs yet: the reward model is not trained")
        nan = float("nan")
        return FitReport(
            nan, nan, nan, nan, ensemble.l2_weight, 0, 0, 0, 0, time.perf_counter() - start
        )

    net, mlp = ensemble.net, ensemble.net.mlp
    with torch.no_grad():
        fragments = net.norm(ensemble.features(dataset.obs, dataset.acts))  # (F, L, D)
    pairs = torch.from_numpy(np.asarray(dataset.pairs, dtype=np.int64))  # (P, 2)
    labels = torch.from_numpy(np.asarray(dataset.labels, dtype=np.float32))  # (P,)
    held_out = validation_mask(n_pairs, cfg)
    train, val = np.flatnonzero(~held_out), np.flatnonzero(held_out)
    samples = _resamples(train, ensemble.size, cfg.bootstrap, rng)  # (K, n_train)

    optimiser = torch.optim.AdamW(mlp.parameters(), lr=cfg.lr, weight_decay=0.0)
    k, length = ensemble.size, fragments.shape[1]
    params = list(mlp.parameters())
    steps = 0
    net.train()
    try:
        for epoch in range(epochs):
            order = torch.from_numpy(rng.permuted(samples, axis=1))
            for batch in order.split(cfg.batch_size, dim=1):  # (K, b) pair indices
                x = fragments[pairs[batch]]  # (K, b, 2, L, D)
                rewards = mlp(x.reshape(k, -1, x.shape[-1])).reshape(*batch.shape, 2, length)
                returns = rewards.sum(dim=-1)
                logits = returns[..., 0] - returns[..., 1]
                ce = binary_cross_entropy_with_logits(logits, labels[batch], reduction="none")
                objective = (ce.mean(dim=1) + ensemble.l2_weight * mlp.l2_penalty()).sum()
                optimiser.zero_grad(set_to_none=True)
                objective.backward()
                optimiser.step()
                steps += 1
                if steps % _FLUSH_EVERY == 0:
                    _flush_denormals(params, optimiser)
            if len(val):
                train_loss, _ = _evaluate(ensemble, fragments, pairs, labels, train)
                val_loss, _ = _evaluate(ensemble, fragments, pairs, labels, val)
                ensemble.l2_weight = _adapt_l2(ensemble.l2_weight, val_loss, train_loss, cfg)
                log.debug(
                    "epoch %d: train %.4f, val %.4f, l2 %.3g",
                    epoch,
                    train_loss,
                    val_loss,
                    ensemble.l2_weight,
                )
    finally:
        _flush_denormals(params, optimiser)
        net.eval()

    if cfg.standardise_output:
        ensemble.standardise_output(dataset.obs, dataset.acts)
    loss, accuracy = _evaluate(ensemble, fragments, pairs, labels, train)
    val_loss, val_accuracy = (
        _evaluate(ensemble, fragments, pairs, labels, val) if len(val) else (math.nan, math.nan)
    )
    return FitReport(
        loss=loss,
        accuracy=accuracy,
        validation_accuracy=val_accuracy,
        validation_loss=val_loss,
        l2_weight=ensemble.l2_weight,
        n_pairs=n_pairs,
        n_validation=len(val),
        epochs=epochs,
        steps=steps,
        seconds=time.perf_counter() - start,
    )


def _check(
    ensemble: RewardEnsemble, dataset: PreferenceDataset, cfg: RewardConfig, epochs: int
) -> None:
    if epochs < 0:
        raise ValueError(f"epochs must be >= 0, got {epochs}")
    if cfg.batch_size < 1:
        raise ValueError(f"batch size must be >= 1, got {cfg.batch_size}")
    dims = (dataset.obs.shape[-1], dataset.acts.shape[-1])
    if dims != (ensemble.obs_dim, ensemble.act_dim):
        raise ValueError(
            f"dataset has obs/act dims {dims}, the ensemble {(ensemble.obs_dim, ensemble.act_dim)}"
        )
    labels = np.asarray(dataset.labels)
    if labels.size and not ((labels >= 0) & (labels <= 1)).all():
        raise ValueError("preference labels must lie in [0, 1]")


def _resamples(
    train: IntArray, members: int, bootstrap: bool, rng: np.random.Generator
) -> IntArray:
    """(K, n_train) pair indices: a bootstrap resample per member, or the pairs themselves."""
    if not bootstrap:
        return np.tile(train, (members, 1))
    return train[rng.integers(0, len(train), size=(members, len(train)))]


@torch.no_grad()
def _evaluate(
    ensemble: RewardEnsemble,
    fragments: Tensor,
    pairs: Tensor,
    labels: Tensor,
    subset: IntArray,
) -> tuple[float, float]:
    """(members' mean cross-entropy, ensemble-mean accuracy over non-ties) on `subset`."""
    k, (_, length, dim) = ensemble.size, fragments.shape
    used = torch.from_numpy(np.asarray(subset, dtype=np.int64))
    rows = pairs[used]  # (S, 2)
    needed, inverse = torch.unique(rows, return_inverse=True)
    returns = ensemble.net.mlp(fragments[needed].reshape(-1, dim)).reshape(k, -1, length).sum(-1)
    diff = returns[:, inverse[:, 0]] - returns[:, inverse[:, 1]]  # (K, S)
    target = labels[used].expand_as(diff)
    loss = binary_cross_entropy_with_logits(diff, target, reduction="none").mean().item()
    mean_diff = diff.mean(dim=0)
    decided = target[0] != 0.5
    if not bool(decided.any()):
        return loss, math.nan
    correct = torch.where(target[0] > 0.5, mean_diff > 0, mean_diff < 0)
    return loss, correct[decided].float().mean().item()


@torch.no_grad()
def _flush_denormals(params: Sequence[Tensor], optimiser: torch.optim.Optimizer) -> None:
    """Set near-subnormal floats in the parameters and their Adam moments to zero, in place.

    Weights of units whose only gradient is the L2 term (dead ReLUs) and their Adam moments
    decay into the subnormal range, where CPU float arithmetic is an order of magnitude
    slower: measured, 100 epochs on 200 pairs took 45 s instead of 6 s, and predictions
    slow down alike. Flushing values a good way above the subnormal range keeps products of
    two small values out of it too; doing it here avoids `torch.set_flush_denormal`, which
    is process state (and only reaches the calling thread).
    """
    moments = (
        t for p in params for t in optimiser.state[p].values() if isinstance(t, Tensor) and t.dim()
    )
    for t in (*params, *moments):
        t.masked_fill_(t.abs() < _TINY, 0.0)


def _adapt_l2(weight: float, val_loss: float, train_loss: float, cfg: RewardConfig) -> float:
    """Christiano et al.'s rule: more L2 when validation loss exceeds `l2_bounds[1]` × the
    training loss (overfitting), less when it is below `l2_bounds[0]` × (underfitting)."""
    low, high = cfg.l2_bounds
    if val_loss > high * train_loss:
        weight *= cfg.l2_factor
    elif val_loss < low * train_loss:
        weight /= cfg.l2_factor
    return float(np.clip(weight, *cfg.l2_range))
