"""How well the learned reward ranks the agent's own states (issue 41, deliverable 1).

The walker's splits failed where the learned reward paid a wide, tilted stance no one had
judged more than the splits the teacher preferred (docs/results/case-studies/README.md).
After every round this measures that directly, on fresh episodes of the current policy:
`episodes` greedy ones (what is evaluated) and `episodes` stochastic ones (what PPO and the
pools see), from their own seeded stream (`rank_rng`), one process:

- ρ: Spearman's rank correlation over all their steps between the reward PPO is paid (the
  ensemble mean, `RewardEnsemble.mean_reward`) and the env's true step reward
  (``info["true_reward"]``, a target env's step score);
- per posture class (walker-splits only, `POSTURES`): the learned reward's mean per step
  over the steps of that class. "split" is a step of a held split by the target's own rule
  (thighs ≥ 90° apart, torso within 60° of vertical, both feet down:
  `envs.scorers.SplitsScorer`), "nonsplit" every other step, and "stance" the failing
  walkers' wide, tilted stance among them (thighs ≥ 90° apart and both feet down, the torso
  past 60°).
"""

from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv
from scipy.stats import spearmanr

from groupwise.envs.body_state import StateReader
from groupwise.envs.scorers import SPLIT_ANGLE, UPRIGHT, WALKER_FEET, split_posture
from groupwise.rl.agents import Agent
from groupwise.rl.rollout import EnvFactory, sample_trajectories
from groupwise.types import FloatArray

RANK_STREAM = 2**24
"""The diagnostic's stream key: `SeedSequence([seed, RANK_STREAM, round])`, apart from the
run's own streams (`run.streams`: rounds, 2**20–2**23)."""

PostureFn = Callable[[FloatArray], dict[str, np.ndarray]]
"""obs (T, obs_dim) -> posture class name -> (T,) bool, which steps are of that class."""


@dataclass(frozen=True)
class RewardRank:
    """The learned reward against the true step reward on the policy's own steps."""

    rho: float
    """Spearman ρ over every step (nan when either is constant)."""
    steps: int
    by_posture: dict[str, float] = field(default_factory=dict)
    """Posture class -> the learned reward's mean per step on its steps (nan: none)."""


def rank_rng(seed: int, round_index: int) -> np.random.Generator:
    """The diagnostic's generator after round `round_index` of a run seeded `seed`."""
    return np.random.default_rng(np.random.SeedSequence([seed, RANK_STREAM, round_index]))


def spearman(learned: FloatArray, true: FloatArray) -> float:
    """Spearman ρ of two (T,) arrays, ties given their mean rank; nan when one is constant.

    Raises:
        ValueError: arrays of different lengths.
    """
    learned, true = np.asarray(learned, dtype=float), np.asarray(true, dtype=float)
    if learned.shape != true.shape:
        raise ValueError(f"need arrays of one shape, got {learned.shape} and {true.shape}")
    if len(learned) < 2 or np.ptp(learned) == 0 or np.ptp(true) == 0:
        return float("nan")
    return float(spearmanr(learned, true).statistic)


def splits_postures(make_env: EnvFactory) -> PostureFn:
    """Walker2d's posture classes (module docstring) from its observations, which hold qpos
    without x: each step's pose is put into a MuJoCo model and its feet measured."""
    env = make_env()
    env.reset(seed=0)
    base = env.unwrapped
    if not isinstance(base, MujocoEnv):
        raise TypeError(f"splits postures need a MuJoCo env, got {type(base).__name__}")
    read, nq = StateReader(base), base.model.nq

    def classes(obs: FloatArray) -> dict[str, np.ndarray]:
        separation, tilt, feet = np.zeros(len(obs)), np.zeros(len(obs)), np.zeros(len(obs))
        for t, o in enumerate(obs):
            base.data.qpos[1:] = o[: nq - 1]
            mujoco.mj_kinematics(base.model, base.data)
            separation[t], tilt[t], feet[t] = split_posture(read())
        wide, down = separation >= SPLIT_ANGLE, feet == len(WALKER_FEET)
        held = wide & down & (tilt <= UPRIGHT)
        return {"split": held, "nonsplit": ~held, "stance": wide & down & (tilt > UPRIGHT)}

    return classes


POSTURES: dict[str, Callable[[EnvFactory], PostureFn]] = {"walker-splits": splits_postures}
"""Target name -> its posture classes, for the targets whose failure has a posture."""


def reward_rank(
    make_env: EnvFactory,
    agent: Agent,
    reward: Callable[[FloatArray, FloatArray], FloatArray],
    episodes: int,
    rng: np.random.Generator,
    postures: PostureFn | None = None,
) -> RewardRank:
    """The diagnostic (module docstring) over `episodes` greedy and `episodes` stochastic
    episodes of `agent`'s policy; `reward` (obs (B, obs_dim), acts (B, act_dim)) -> (B,) is
    the learned reward PPO is paid.

    Raises:
        ValueError: `episodes` < 1.
    """
    if episodes < 1:
        raise ValueError(f"need at least one episode of each kind, got {episodes}")
    trajectories = [
        t
        for greedy in (True, False)
        for t in sample_trajectories(
            make_env, agent.policy(deterministic=greedy), episodes, rng, processes=1
        )
    ]
    obs = np.concatenate([t.obs for t in trajectories])
    acts = np.concatenate([t.acts for t in trajectories])
    true = np.concatenate([t.true_rewards for t in trajectories])
    learned = np.asarray(reward(obs, acts), dtype=float)
    by_posture = {}
    if postures is not None:
        by_posture = {
            name: float(learned[steps].mean()) if steps.any() else float("nan")
            for name, steps in postures(obs).items()
        }
    return RewardRank(rho=spearman(learned, true), steps=len(true), by_posture=by_posture)
