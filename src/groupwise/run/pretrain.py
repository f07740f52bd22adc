"""Setup hooks a run composes before round 0, and unsupervised pre-training, the one that
measured a gain (issue 20; PEBBLE, Lee et al. 2021, §4.1).

A setup hook is a small object with one verb, `before_first_round(run, callback)`, that the
round driver calls once on a run whose agent has not trained yet (`before_first_round`), as
Stable-Baselines3 calls a callback's `_on_training_start`; the config says which hooks a run
has (`setup_hooks`), so neither `begin_round` nor `end_round` branches on them:

    before_first_round(run, callback)   # each of setup_hooks(run.cfg), on a fresh run only
    run_rounds(run, feedback)           # does it itself

`StateEntropyPretraining`: a random policy rarely shows a case study's behaviour, so round
0's pool holds nothing better to tell apart (a random cheetah's upness 0.009 ± 0.003,
docs/case-studies.md). With `TrainingConfig.pretrain_steps` > 0 the run's PPO first trains
that many steps on a state-entropy bonus (`rl.state_entropy.StateEntropyReward`) instead of
the learned reward, which the first pool is then sampled from.

Its PPO seed comes from `run.streams.pretrain_rng`, so a resumed run repeats it: a run
restored after a round never pre-trains again (the checkpoint holds the result), a run
that crashed before round 0 was committed pre-trains again, the same way.
"""

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from groupwise.config import RunConfig
from groupwise.rl.state_entropy import StateEntropyReward
from groupwise.run.progress import RunCallback, as_callback
from groupwise.run.run import Run
from groupwise.run.streams import pretrain_rng

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PretrainReport:
    """What pre-training did."""

    steps: int
    """PPO env steps it took (whole rollouts)."""
    seconds: float
    bonus_means: tuple[float, ...]
    """The mean entropy bonus log(c + kNN distance) of each block of states in order
    (`StateEntropyReward.bonus_means`: relative to the recent states' own spread)."""


class SetupHook(Protocol):
    """Something a run does once before round 0 (`before_first_round`)."""

    def before_first_round(self, run: Run, callback: RunCallback) -> None:
        """Prepare the fresh `run` (no round yet, an untrained agent); `callback` hears
        its phases."""
        ...


@dataclass(frozen=True)
class StateEntropyPretraining:
    """`steps` PPO steps on a state-entropy bonus before round 0 (module docstring): the
    k-nearest-neighbour entropy estimate with `k` neighbours among the `states` most recent
    states, then the policy's action noise set to log σ `teach_log_std` when given
    (`TrainingConfig.pretrain_steps`, `.pretrain_k`, `.pretrain_states`, `.teach_log_std`)."""

    steps: int
    k: int = 5
    states: int = 10_000
    teach_log_std: float | None = None

    def before_first_round(self, run: Run, callback: RunCallback) -> None:
        self.train(run, callback=callback)

    def train(
        self,
        run: Run,
        rng: np.random.Generator | None = None,
        callback: RunCallback | None = None,
    ) -> PretrainReport:
        """Train the run's PPO agent, seeded from `rng` (default: `pretrain_rng` of the
        run's seed); `callback` hears the phase "pretrain" in PPO steps.

        Raises:
            TypeError: the run's agent is not groupwise's own PPO.
            ValueError: the run already has rounds or its agent has trained (pre-training
                comes first).
        """
        if run.next_round != 0 or run.agent.num_timesteps != 0:
            raise ValueError(
                f"pre-training comes before round 0 and any PPO; the run is at round "
                f"{run.next_round} after {run.agent.num_timesteps} PPO steps"
            )
        agent, callback = run.ppo, as_callback(callback)
        rng = rng or pretrain_rng(run.cfg.loop.seed)
        bonus = StateEntropyReward(k=self.k, capacity=self.states)
        before = agent.num_timesteps
        tick = time.perf_counter()
        agent.pretrain(
            bonus,
            self.steps,
            int(rng.integers(2**31 - 1)),
            report=lambda done, total: callback.on_phase("pretrain", done, total),
            then_log_std=self.teach_log_std,
        )
        report = PretrainReport(
            steps=agent.num_timesteps - before,
            seconds=time.perf_counter() - tick,
            bonus_means=tuple(bonus.bonus_means),
        )
        log.info(
            "pre-trained %d steps on the state-entropy bonus in %.0f s%s",
            report.steps,
            report.seconds,
            "" if self.teach_log_std is None else f"; teaching at log σ {self.teach_log_std:g}",
        )
        return report


def setup_hooks(cfg: RunConfig) -> tuple[SetupHook, ...]:
    """The setup hooks `cfg` asks for: state-entropy pre-training when
    `training.pretrain_steps` > 0."""
    pretraining = _pretraining(cfg)
    return () if pretraining is None else (pretraining,)


def before_first_round(
    run: Run, callback: RunCallback | None = None, hooks: Sequence[SetupHook] | None = None
) -> bool:
    """Run `hooks` (default: `setup_hooks(run.cfg)`) in order when `run` is fresh (no round
    yet, an untrained agent); False when it was not (a restored run: nothing to do)."""
    if run.next_round != 0 or run.agent.num_timesteps != 0:
        return False
    callback = as_callback(callback)
    for hook in setup_hooks(run.cfg) if hooks is None else hooks:
        hook.before_first_round(run, callback)
    return True


def pretrain(
    run: Run, rng: np.random.Generator | None = None, callback: RunCallback | None = None
) -> PretrainReport | None:
    """Pre-train the run's agent as its config asks (`StateEntropyPretraining.train` of
    `training.pretrain_steps` steps); None when that is 0.

    Raises:
        TypeError: the run's agent is not groupwise's own PPO.
        ValueError: the run already has rounds or its agent has trained.
    """
    pretraining = _pretraining(run.cfg)
    return None if pretraining is None else pretraining.train(run, rng, callback)


def _pretraining(cfg: RunConfig) -> StateEntropyPretraining | None:
    training = cfg.training
    if training.pretrain_steps == 0:
        return None
    return StateEntropyPretraining(
        training.pretrain_steps,
        training.pretrain_k,
        training.pretrain_states,
        training.teach_log_std,
    )
