"""Re-initialising the reward ensemble (issue 41, after PoLiCER, ICLR 2026).

PoLiCER warns that a reward model refined only near the current policy gives "overly
localised guidance" and starts it again when the critic says it overestimates. A
warm-started ensemble (`RewardConfig.warm_start`) carries every earlier round's mistakes
into the next fit; a reset draws fresh member weights and refits them on the whole
cumulative dataset (`bradley_terry.fit` always trains on all of it), with round 0's longer
training (`RewardConfig.initial_epoch_multiplier`).

Two rules, either or both:
- the schedule: before the fit of every round r ≥ 1 with r % `every` == 0;
- the signal: the learned reward overestimates the agent's own behaviour, i.e. its mean per
  step over the round's newest behaviours (the pool, sampled from the current policy) exceeds
  its mean per step over the behaviours the teacher preferred so far (the winning side of
  every decided pair) by more than `margin` sds of the per-step reward over the dataset's
  fragments. Read with the ensemble PPO trained on, before the round's fit.
"""

from dataclasses import dataclass

import numpy as np

from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward.ensemble import RewardEnsemble
from groupwise.types import FloatArray


@dataclass(frozen=True)
class ResetRule:
    """When to re-initialise the ensemble before a round's fit (module docstring); None
    switches that rule off."""

    every: int | None = None
    margin: float | None = None

    def __post_init__(self) -> None:
        if self.every is not None and self.every < 1:
            raise ValueError(f"reset every >= 1 rounds, got {self.every}")

    def reason(
        self,
        round_index: int,
        ensemble: RewardEnsemble,
        dataset: PreferenceDataset,
        latest_obs: FloatArray,
        latest_acts: FloatArray,
    ) -> str | None:
        """ "schedule", "signal" or None (no reset) before round `round_index`'s fit, for the
        dataset as it is before that fit. `latest_obs` (N, L, obs_dim) and `latest_acts`
        (N, L, act_dim) are the agent's newest behaviours. Round 0, and a dataset without
        a decided pair, never reset."""
        if round_index == 0 or len(dataset) == 0:
            return None
        if self.every is not None and round_index % self.every == 0:
            return "schedule"
        if self.margin is not None and len(latest_obs):
            gap = overestimation(ensemble, dataset, latest_obs, latest_acts)
            if gap > self.margin:
                return "signal"
        return None


def overestimation(
    ensemble: RewardEnsemble,
    dataset: PreferenceDataset,
    latest_obs: FloatArray,
    latest_acts: FloatArray,
) -> float:
    """(mean reward per step on the latest behaviours − that on the preferred ones) / the sd
    of the reward per step over all the dataset's fragments; nan without a decided pair.
    The reward is the one PPO is paid (`RewardEnsemble.mean_reward`)."""
    winners = preferred(dataset)
    if len(winners) == 0:
        return float("nan")
    every = _step_rewards(ensemble, dataset.obs, dataset.acts)
    liked = _step_rewards(ensemble, dataset.obs[winners], dataset.acts[winners])
    latest = _step_rewards(ensemble, latest_obs, latest_acts)
    scale = float(every.std())
    if not scale > 0:
        return float("nan")
    return float((latest.mean() - liked.mean()) / scale)


def preferred(dataset: PreferenceDataset) -> np.ndarray:
    """Rows of the dataset's fragments that won at least one pair (ties decide nothing)."""
    pairs, labels = dataset.pairs, dataset.labels
    won = np.concatenate([pairs[labels > 0.5, 0], pairs[labels < 0.5, 1]])
    return np.unique(won)


def _step_rewards(ensemble: RewardEnsemble, obs: FloatArray, acts: FloatArray) -> FloatArray:
    return ensemble.mean_reward(obs.reshape(-1, obs.shape[-1]), acts.reshape(-1, acts.shape[-1]))
