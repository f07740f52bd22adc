"""The case studies' target scores (paper §"Example Cases"), computed step by step.

Each scorer follows one episode: made from the episode's first state and the env's step
duration, it is given every following state and returns that step's score (the per-step
true reward of a target env, so fragment returns and simulated decision-makers work as for
any env), and `total()` is the episode's target score so far. The thresholds and their
reasons are in docs/case-studies.md; the numbers were chosen against random-policy episodes
(20 per env, seed 0 …): a random Hopper rolls backwards on the floor up to 1.2 turns an
episode, but turns by at most 0.41 while its centre of mass is at least 0.5 m high; a random
HalfCheetah raises its front by at most 24°; a random Walker2d falls within a second.
"""

import math

import numpy as np

from groupwise.envs.body_state import BodyState

TURN = 2.0 * math.pi


def wrap_angle(angle: float) -> float:
    """`angle` in [−π, π), rad: the difference of two pitches however they were recorded."""
    return (angle + math.pi) % TURN - math.pi


def ramp(x: float, low: float, high: float) -> float:
    """0 at or below `low`, 1 at or above `high`, linear between."""
    return float(np.clip((x - low) / (high - low), 0.0, 1.0))


class BackflipScorer:
    """Backward turns of the torso while the robot is up (Hopper).

    Step score: the torso's backward rotation rate in turns per second, counted only while
    the robot's centre of mass is at least `min_com_height` high (a flip, not a roll on the
    floor); forward rotation counts negative. Total: the net backward turns so far, so one
    backflip adds 1 and one forward flip subtracts 1. Pitch differences are unwrapped, so
    states whose pitch was wrapped to (−π, π] score the same.
    """

    def __init__(self, first: BodyState, dt: float, min_com_height: float = 0.5) -> None:
        self.dt = dt
        self.min_com_height = min_com_height
        self._pitch = first.pitch
        self.turns = 0.0

    def step(self, state: BodyState) -> float:
        delta = wrap_angle(state.pitch - self._pitch)
        self._pitch = state.pitch
        if state.com_height < self.min_com_height:
            return 0.0
        backward = -delta / TURN  # positive pitch tips the top forward
        self.turns += backward
        return backward / self.dt

    def total(self) -> float:
        return self.turns


def upness(state: BodyState) -> float:
    """How much a HalfCheetah stands on its back legs, in [0, 1]: its front raised 60–120°
    (ramping from 30° and down to 150°, past which it topples over backwards) with the rear
    of its torso held 0.3 m or more above the floor (ramping from 0.1 m, so sitting on its
    rear counts as sitting)."""
    raised = math.degrees(-wrap_angle(state.pitch))  # front up is negative pitch
    posture = ramp(raised, 30.0, 60.0) * (1.0 - ramp(raised, 120.0, 150.0))
    return posture * ramp(state.bottoms["torso"], 0.1, 0.3)


class StandSitScorer:
    """Standing up on the back legs and sitting down again, in turns (HalfCheetah).

    Phases with hysteresis: the cheetah stands once `upness` reaches `stand_at` and sits once
    it drops to `sit_at`; a sit that ends a stand of at least `min_stand_s` completes a
    cycle. Step score: the step's `upness` plus `cycle_bonus` on the step a cycle completes
    (worth 1.5 s of standing at 20 steps/s, so a fragment that shows a sit-down beats one
    that only stands; wobbling about a threshold completes nothing). Total: completed cycles
    plus half the episode's mean upness so far, so standing without sitting down scores at
    most 0.5 and a total ≥ 1 means at least one stand-up and sit-down.
    """

    def __init__(
        self,
        first: BodyState,
        dt: float,
        stand_at: float = 0.8,
        sit_at: float = 0.2,
        min_stand_s: float = 0.5,
        cycle_bonus: float = 30.0,
    ) -> None:
        self.dt = dt
        self.stand_at, self.sit_at = stand_at, sit_at
        self.min_stand_s, self.cycle_bonus = min_stand_s, cycle_bonus
        self.standing = upness(first) >= stand_at
        self._stand_steps = 0
        self._steps = 0
        self._upness = 0.0
        self.cycles = 0

    def step(self, state: BodyState) -> float:
        u = upness(state)
        self._steps += 1
        self._upness += u
        if not self.standing:
            if u >= self.stand_at:
                self.standing, self._stand_steps = True, 0
            return u
        if u > self.sit_at:
            self._stand_steps += 1
            return u
        self.standing = False
        if self._stand_steps * self.dt < self.min_stand_s:
            return u
        self.cycles += 1
        return u + self.cycle_bonus

    def total(self) -> float:
        mean = self._upness / self._steps if self._steps else 0.0
        return self.cycles + 0.5 * mean


SPLIT_ANGLE = math.radians(90.0)
"""Thigh separation of a split (and the unit of the splits' step score)."""
UPRIGHT = math.radians(60.0)
"""Most torso tilt from vertical that counts as upright."""
GROUNDED = 0.05
"""A foot whose lowest point is at most this high (m) is on the floor."""
WALKER_FEET = ("foot_geom", "foot_left_geom")


class SplitsScorer:
    """The splits (Walker2d): thighs far apart, torso upright, both feet on the floor.

    Step score: the thighs' separation in units of 90° × uprightness (1 within 60° of
    vertical, falling to 0 at 90°) × the share of feet on the floor (0, ½, 1); a 90° split
    scores 1 a step. Total: the longest time, s, a split of at least 90° was held with the
    torso within 60° of vertical and both feet down. The walker's hips only swing backwards
    (−150°…0° from the torso), so a symmetric 90° split leans the torso 45° backwards.
    """

    def __init__(self, first: BodyState, dt: float) -> None:
        self.dt = dt
        self._run = 0
        self.longest = 0

    def step(self, state: BodyState) -> float:
        separation = abs(float(state.qpos[3] - state.qpos[6]))  # right, left thigh
        tilt = abs(wrap_angle(state.pitch))
        feet = [state.bottoms[foot] <= GROUNDED for foot in WALKER_FEET]
        holding = separation >= SPLIT_ANGLE and tilt <= UPRIGHT and all(feet)
        self._run = self._run + 1 if holding else 0
        self.longest = max(self.longest, self._run)
        upright = 1.0 - ramp(tilt, UPRIGHT, math.pi / 2)
        return separation / SPLIT_ANGLE * upright * (sum(feet) / len(feet))

    def total(self) -> float:
        return self.longest * self.dt
