"""Named ablations of a study cell: one change to its `RunConfig` each (SPEC §8, issue 12).

An ablation's cells live beside the main study's, in ``OUT/{name}/{env}/{dm}/seed-{k}/``
(`cells.Cell.condition`), and the report sets their final returns beside the default cells'.
Each one reproduces a choice of the comparison the paper made that our defaults do not:

- ``capped``: each round keeps at most as many preference pairs as it asked comparisons, the
  pairwise DM's count (SPEC §8's capped ablation; ``--cap-pairs``).
- ``pairs2x``: every judgement yields twice the pairs its derivation gives (the paper's
  reference code draws twice as many pairs per judgement; `LoopConfig.pair_oversample`).
- ``no-reward-norm``: PPO sees the learned reward unscaled (neither standardised per step
  nor scaled by a running return std: `PPOConfig.standardise_reward`, `normalize_reward`).
- ``obs-only``: the reward members see the observation alone, not [obs ; act]
  (`RewardConfig.use_actions` off; ARCHITECTURE.md, "Reward inputs").
- ``calibrated``: the simulated teacher is wrong as often as the paper's people (12 % of
  behaviour pairs of unequal return, its noise set per pool: `teachers.calibration`) instead
  of SPEC §7's fixed σ per step.
- ``noiseless``: the simulated teacher is never wrong (σ = 0), as the scripted teacher of
  the preference-based RL benchmarks (B-Pref; PEBBLE, SURF, QPA, PPE) is: their published
  tables are read beside these cells (issue 42's DMC table).
"""

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

from groupwise.config import RunConfig
from groupwise.teachers.calibration import PEOPLE_LABEL_ERROR


@dataclass(frozen=True)
class Ablation:
    """One change to a cell's configuration; call it on the config of the default cell."""

    summary: str
    """One line for ``--help`` and the report."""
    change: Callable[[RunConfig], RunConfig]
    """The config of the default cell → the config of the ablated cell."""

    def __call__(self, config: RunConfig) -> RunConfig:
        return self.change(config)


def _capped(config: RunConfig) -> RunConfig:
    return dataclasses.replace(config, loop=dataclasses.replace(config.loop, pair_cap=1.0))


def _pairs2x(config: RunConfig) -> RunConfig:
    return dataclasses.replace(config, loop=dataclasses.replace(config.loop, pair_oversample=2.0))


def _no_reward_norm(config: RunConfig) -> RunConfig:
    ppo = dataclasses.replace(config.ppo, normalize_reward=False, standardise_reward=False)
    return dataclasses.replace(config, ppo=ppo)


def _obs_only(config: RunConfig) -> RunConfig:
    return dataclasses.replace(config, reward=dataclasses.replace(config.reward, use_actions=False))


def _noiseless(config: RunConfig) -> RunConfig:
    return dataclasses.replace(config, teacher=dataclasses.replace(config.teacher, noise_sigma=0.0))


def _calibrated(config: RunConfig) -> RunConfig:
    teacher = dataclasses.replace(config.teacher, label_error=PEOPLE_LABEL_ERROR)
    return dataclasses.replace(config, teacher=teacher)


ABLATIONS: dict[str, Ablation] = {
    "capped": Ablation(
        "at most one preference pair per comparison and round (pair_cap 1.0)",
        _capped,
    ),
    "pairs2x": Ablation(
        "twice the preference pairs per judgement, as the paper's reference code draws "
        "(pair_oversample 2.0)",
        _pairs2x,
    ),
    "no-reward-norm": Ablation(
        "PPO on the unscaled learned reward (standardise_reward and normalize_reward off)",
        _no_reward_norm,
    ),
    "obs-only": Ablation(
        "reward members over the observation alone (use_actions off)",
        _obs_only,
    ),
    "calibrated": Ablation(
        f"a teacher wrong as often as the paper's people (label_error {PEOPLE_LABEL_ERROR})",
        _calibrated,
    ),
    "noiseless": Ablation(
        "a teacher that is never wrong (noise_sigma 0), as the benchmarks' scripted teacher",
        _noiseless,
    ),
}
"""Every ablation by name; the name is also its directory in a study (`cells.Cell`)."""


def ablate(config: RunConfig, name: str | None) -> RunConfig:
    """`config` changed by ablation `name`; None leaves it as it is.

    Raises:
        ValueError: no ablation `name`.
    """
    if name is None:
        return config
    if name not in ABLATIONS:
        raise ValueError(f"unknown ablation {name!r}; choose from {', '.join(ABLATIONS)}")
    return ABLATIONS[name](config)
