"""Target tasks without a reward: the paper's three case studies as envs with a scripted score.

Each target env (``groupwise/Hopper-backflip-v0``, ``groupwise/HalfCheetah-standup-v0``,
``groupwise/Walker2d-splits-v0``) is its base MuJoCo env with a fixed horizon and no
termination, whose reward is always 0.0, so nothing but the learned reward reaches PPO. The
target's per-step score goes into ``info["target_score"]`` and ``info["true_reward"]``: the
loop's evaluation and the simulated decision-makers use it as they use any env's true reward
(fragment return = sum of its steps' scores, plus the SPEC §7 noise). The episode's target
score so far is ``info["target_total"]``; a `Target` states it, with its success thresholds,
up front. Definitions and reasons: docs/case-studies.md.
"""

import importlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

from groupwise.envs.body_state import BodyState, StateReader
from groupwise.envs.rendering import DEFAULT_FRAME_SIZE, FastMujocoRendering
from groupwise.envs.scorers import BackflipScorer, SplitsScorer, StandSitScorer
from groupwise.envs.true_reward import TRUE_REWARD_KEY
from groupwise.types import FloatArray

TARGET_SCORE_KEY = "target_score"
"""The `info` key of a target env's per-step score (also under ``"true_reward"``)."""
TARGET_TOTAL_KEY = "target_total"
"""The `info` key of the episode's target score so far (its value at the last step is the
episode's target score)."""

SCORE_TOLERANCE = 1e-9
"""Scores within this of a threshold reach it: a sum of per-step rotations rounds off (one
exact turn in 100 steps sums to 1 − 8e-16)."""


class EpisodeScorer(Protocol):
    """Scores one episode as it runs (`groupwise.envs.scorers`)."""

    def step(self, state: BodyState) -> float:
        """The score of the step that ended in `state`."""
        ...

    def total(self) -> float:
        """The episode's target score so far."""
        ...


@dataclass(frozen=True)
class Target:
    """A behaviour without a reward, and the score that says how well it is done."""

    name: str
    """The case-study name, e.g. "hopper-backflip"."""
    env: str
    """Short name of its env, e.g. "Hopper-backflip" (Gymnasium id ``groupwise/<env>-v0``)."""
    base: str
    """The groupwise env it modifies, e.g. "Hopper"."""
    unit: str
    """What the episode score counts, e.g. "backward turns"."""
    step_unit: str
    """The unit of a per-step score, e.g. "rad/s" (a sum of them, the true return, is in
    it too: it is not the episode score)."""
    threshold: float
    """An episode succeeds when its target score is at least this."""
    stretch: float
    """The more ambitious level (e.g. the paper's double backflip)."""
    success: str
    """When an episode succeeds, in words a person reads beside the env's name, with
    `threshold` in it, e.g. "a split held ≥ 1 s"."""
    moment_s: float
    """How long the behaviour takes to show, s: the span of the five-frame strip."""
    description: str
    """The definition in one paragraph."""
    start: Callable[[BodyState, float], EpisodeScorer]
    """A fresh scorer from an episode's first state and the env's step duration, s."""

    def step_scores(self, states: Sequence[BodyState], dt: float) -> FloatArray:
        """Per-step scores (T,) of an episode given as its T + 1 states, first state first."""
        scorer = self.start(states[0], dt)
        return np.array([scorer.step(state) for state in states[1:]], dtype=np.float64)

    def episode_score(self, states: Sequence[BodyState], dt: float) -> float:
        """The target score of an episode given as its states, first state first."""
        scorer = self.start(states[0], dt)
        for state in states[1:]:
            scorer.step(state)
        return scorer.total()

    def succeeds(self, score: float) -> bool:
        """Whether an episode's target score reaches `threshold`."""
        return score >= self.threshold - SCORE_TOLERANCE

    def stretches(self, score: float) -> bool:
        """Whether an episode's target score reaches `stretch`."""
        return score >= self.stretch - SCORE_TOLERANCE


TARGETS: dict[str, Target] = {
    target.name: target
    for target in (
        Target(
            name="hopper-backflip",
            env="Hopper-backflip",
            base="Hopper",
            unit="backward turns",
            step_unit="rad/s",
            threshold=1.0,
            stretch=2.0,
            success="≥ 1 backward turn",
            moment_s=1.0,
            description=(
                "net backward turns of the torso made while the centre of mass is at least "
                "0.5 m high; step score: backward rotation, rad/s, at such steps"
            ),
            start=BackflipScorer,
        ),
        Target(
            name="halfcheetah-standup",
            env="HalfCheetah-standup",
            base="HalfCheetah",
            unit="stand-sit cycles + half the mean upness",
            step_unit="rad",
            threshold=1.0,
            stretch=3.0,
            success="≥ 1 stand-sit cycle",
            moment_s=3.0,
            description=(
                "completed cycles of standing on the back legs (upness >= 0.8: front raised "
                ">= 48°, rear of the torso >= 0.26 m up) for >= 0.5 s and sitting down again "
                "(upness <= 0.2), plus half the mean upness; step score: the front's raise, "
                "rad, up to 60°, + 1.5 s of that when a cycle completes"
            ),
            start=StandSitScorer,
        ),
        Target(
            name="walker-splits",
            env="Walker2d-splits",
            base="Walker2d",
            unit="s held",
            step_unit="rad",
            threshold=1.0,
            stretch=4.0,
            success="a split held ≥ 1 s",
            moment_s=1.0,
            description=(
                "longest hold, s, of a split: thighs >= 90° apart, torso within 60° of "
                "vertical, both feet on the floor; step score: separation, rad, up to 90°, × "
                "uprightness × share of feet down (its most, π/2, is a split held)"
            ),
            start=SplitsScorer,
        ),
    )
}
"""The case studies' targets by name (`groupwise case-study --target`)."""


class TargetScoreInfo(gym.Wrapper[Any, Any, Any, Any]):
    """Zero reward; the target's step score in `info` as the true reward (module docstring)."""

    def __init__(self, env: gym.Env[Any, Any], target: Target) -> None:
        super().__init__(env)
        base = env.unwrapped
        if not isinstance(base, MujocoEnv):
            raise TypeError(f"a target needs a MuJoCo env, got {type(base).__name__}")
        self._base: MujocoEnv = base
        self._read = StateReader(base)
        self.target = target
        self._scorer: EpisodeScorer | None = None

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        self._scorer = self.target.start(self._read(), self._base.dt)
        return obs, info

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        if self._scorer is None:
            raise RuntimeError("reset the env before stepping it")
        obs, _, terminated, truncated, info = self.env.step(action)
        score = self._scorer.step(self._read())
        info[TARGET_SCORE_KEY] = info[TRUE_REWARD_KEY] = score
        info[TARGET_TOTAL_KEY] = self._scorer.total()
        return obs, 0.0, terminated, truncated, info


def _make(
    target: str,
    env_class: str,
    render_mode: str | None,
    width: int,
    height: int,
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """`env_class` is "module:Class", imported only here: importing `groupwise.envs` must
    not need Gymnasium's v5 MuJoCo envs (the peer benchmark's imitation venv has v4 only)."""
    module, _, name = env_class.partition(":")
    base_class: type[MujocoEnv] = getattr(importlib.import_module(module), name)
    env = base_class(render_mode=render_mode, width=width, height=height, **kwargs)
    return TargetScoreInfo(FastMujocoRendering(env, tracked_body="torso"), TARGETS[target])


def make_hopper_backflip(
    render_mode: str | None = None,
    width: int = DEFAULT_FRAME_SIZE[0],
    height: int = DEFAULT_FRAME_SIZE[1],
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """Hopper-v5 that keeps going when unhealthy (a flip is), reward 0, backflip score."""
    return _make(
        "hopper-backflip",
        "groupwise.envs.lean_mujoco:LeanHopperEnv",
        render_mode,
        width,
        height,
        terminate_when_unhealthy=False,
        **kwargs,
    )


def make_half_cheetah_standup(
    render_mode: str | None = None,
    width: int = DEFAULT_FRAME_SIZE[0],
    height: int = DEFAULT_FRAME_SIZE[1],
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """HalfCheetah-v5, reward 0, stand-up-and-sit score."""
    return _make(
        "halfcheetah-standup",
        "groupwise.envs.lean_mujoco:LeanHalfCheetahEnv",
        render_mode,
        width,
        height,
        **kwargs,
    )


def make_walker2d_splits(
    render_mode: str | None = None,
    width: int = DEFAULT_FRAME_SIZE[0],
    height: int = DEFAULT_FRAME_SIZE[1],
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """Walker2d-v5 that keeps going when unhealthy, reward 0, splits score."""
    return _make(
        "walker-splits",
        "groupwise.envs.lean_mujoco:LeanWalker2dEnv",
        render_mode,
        width,
        height,
        terminate_when_unhealthy=False,
        **kwargs,
    )
