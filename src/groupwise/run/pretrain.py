"""Unsupervised pre-training before round 0 (issue 20; PEBBLE, Lee et al. 2021, §4.1).

A random policy rarely shows a case study's behaviour, so round 0's pool holds nothing
better to tell apart (a random cheetah's upness 0.009 ± 0.003, docs/case-studies.md). With
`TrainingConfig.pretrain_steps` > 0 the run's PPO first trains that many steps on a
state-entropy bonus (`rl.state_entropy.StateEntropyReward`) instead of the learned reward,
which the first pool is then sampled from:

    report = pretrain(run)          # before round 0; None when pretrain_steps is 0
    run_rounds(run, feedback)       # does it itself when the agent has not trained yet

Its PPO seed comes from `run.streams.pretrain_rng`, so a resumed run repeats it: a run
restored after a round never pre-trains again (the checkpoint holds the result), a run
that crashed before round 0 was committed pre-trains again, the same way.
"""

import logging
import time
from dataclasses import dataclass

import numpy as np

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


def pretrain(
    run: Run, rng: np.random.Generator | None = None, callback: RunCallback | None = None
) -> PretrainReport | None:
    """Train the run's PPO agent `run.cfg.training.pretrain_steps` steps on the state-entropy
    bonus (module docstring), seeded from `rng` (default: `pretrain_rng` of the run's seed);
    `callback` hears the phase "pretrain" in PPO steps. None when there is nothing to do.

    Raises:
        TypeError: the run's agent is not groupwise's own PPO.
        ValueError: the run already has rounds or its agent has trained (pre-training
            comes first).
    """
    training = run.cfg.training
    if training.pretrain_steps == 0:
        return None
    if run.next_round != 0 or run.agent.num_timesteps != 0:
        raise ValueError(
            f"pre-training comes before round 0 and any PPO; the run is at round "
            f"{run.next_round} after {run.agent.num_timesteps} PPO steps"
        )
    agent, callback = run.ppo, as_callback(callback)
    rng = rng or pretrain_rng(run.cfg.loop.seed)
    bonus = StateEntropyReward(k=training.pretrain_k, capacity=training.pretrain_states)
    before = agent.num_timesteps
    tick = time.perf_counter()
    agent.pretrain(
        bonus,
        training.pretrain_steps,
        int(rng.integers(2**31 - 1)),
        report=lambda done, total: callback.on_phase("pretrain", done, total),
    )
    report = PretrainReport(
        steps=agent.num_timesteps - before,
        seconds=time.perf_counter() - tick,
        bonus_means=tuple(bonus.bonus_means),
    )
    log.info(
        "pre-trained %d steps on the state-entropy bonus in %.0f s", report.steps, report.seconds
    )
    return report
