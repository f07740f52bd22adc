"""The lean MuJoCo envs step bit for bit like Gymnasium's stock v5 envs (issue 22)."""

from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.envs.mujoco.half_cheetah_v5 import HalfCheetahEnv
from gymnasium.envs.mujoco.hopper_v5 import HopperEnv
from gymnasium.envs.mujoco.walker2d_v5 import Walker2dEnv
from gymnasium.wrappers import TimeLimit

from groupwise.envs import make_env
from groupwise.envs.lean_mujoco import LeanHalfCheetahEnv, LeanHopperEnv, LeanWalker2dEnv
from groupwise.envs.rendering import FastMujocoRendering
from groupwise.envs.targets import TARGETS, TargetScoreInfo

STEPS = 1500
"""Steps per comparison: several episodes, each ended by a termination or the time limit."""
LIMIT = 200

PAIRS = {
    "Hopper": (HopperEnv, LeanHopperEnv),
    "Walker2d": (Walker2dEnv, LeanWalker2dEnv),
    "HalfCheetah": (HalfCheetahEnv, LeanHalfCheetahEnv),
}


def _physics(env: gym.Env[Any, Any]) -> dict[str, np.ndarray]:
    """Everything a step leaves behind that anything reads: the full physics state, the
    forces computed after the step, and the positions the target scores and frames read."""
    base: Any = env.unwrapped
    model, data = base.model, base.data
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    return {
        "state": state,
        **{
            name: getattr(data, name).copy()
            for name in ("qacc", "cacc", "cfrc_int", "cfrc_ext", "subtree_com", "xpos", "xmat")
        },
        "geom_xpos": data.geom_xpos.copy(),
        "geom_xmat": data.geom_xmat.copy(),
    }


def _assert_same_info(stock: dict[str, Any], lean: dict[str, Any]) -> None:
    assert stock.keys() == lean.keys()
    for key in stock:
        assert type(stock[key]) is type(lean[key]), key
        assert np.array_equal(stock[key], lean[key]), key


def _assert_same_physics(stock: gym.Env[Any, Any], lean: gym.Env[Any, Any]) -> None:
    for name, value in _physics(stock).items():
        assert np.array_equal(value, _physics(lean)[name]), name


def _side_by_side(stock: gym.Env[Any, Any], lean: gym.Env[Any, Any], seed: int) -> dict[str, int]:
    """Step both envs `STEPS` times with the same random actions, resetting both with the same
    seed whenever an episode ends, and assert every output is identical; the counts of ends."""
    rng = np.random.default_rng(seed)
    low, high = stock.action_space.low, stock.action_space.high
    ends = {"terminated": 0, "truncated": 0}
    reset_seed = int(rng.integers(2**31))
    obs_s, info_s = stock.reset(seed=reset_seed)
    obs_l, info_l = lean.reset(seed=reset_seed)
    for t in range(STEPS):
        assert np.array_equal(obs_s, obs_l)
        _assert_same_info(info_s, info_l)
        _assert_same_physics(stock, lean)
        action = rng.uniform(low * 1.2, high * 1.2)  # some beyond the bounds, as PPO's may be
        if t % 2:
            action = action.astype(np.float32)  # policies give float32; the cost's dtype follows
        obs_s, reward_s, term_s, trunc_s, info_s = stock.step(action)
        obs_l, reward_l, term_l, trunc_l, info_l = lean.step(action.copy())
        assert type(reward_s) is type(reward_l) and np.array_equal(reward_s, reward_l)
        assert (term_s, trunc_s) == (term_l, trunc_l)
        assert type(term_s) is type(term_l)
        if term_s or trunc_s:
            ends["terminated" if term_s else "truncated"] += 1
            reset_seed = int(rng.integers(2**31))
            obs_s, info_s = stock.reset(seed=reset_seed)
            obs_l, info_l = lean.reset(seed=reset_seed)
    return ends


@pytest.mark.parametrize("name", PAIRS)
@pytest.mark.parametrize("terminate", [True, False])
def test_lean_env_steps_bit_for_bit_like_the_stock_env(name: str, terminate: bool) -> None:
    stock_class, lean_class = PAIRS[name]
    kwargs = {} if name == "HalfCheetah" else {"terminate_when_unhealthy": terminate}
    stock = TimeLimit(stock_class(**kwargs), LIMIT)
    lean = TimeLimit(lean_class(**kwargs), LIMIT)
    ends = _side_by_side(stock, lean, seed=len(name) + terminate)
    if terminate and name != "HalfCheetah":
        assert ends["terminated"] >= 3  # random actions topple the robot within a few steps
    else:
        assert ends["truncated"] >= 3 and ends["terminated"] == 0


@pytest.mark.parametrize("name", ["Hopper", "Walker2d"])
def test_lean_env_keeps_the_stock_options(name: str) -> None:
    """Positions kept in the observation and narrower health ranges take the same paths."""
    stock_class, lean_class = PAIRS[name]
    kwargs: dict[str, Any] = {
        "exclude_current_positions_from_observation": False,
        "healthy_z_range": (0.9, 2.0),
    }
    if name == "Hopper":
        kwargs["healthy_state_range"] = (-5.0, 5.0)
    ends = _side_by_side(
        TimeLimit(stock_class(**kwargs), LIMIT), TimeLimit(lean_class(**kwargs), LIMIT), seed=7
    )
    assert ends["terminated"] >= 1


@pytest.mark.parametrize("target", sorted(TARGETS))
def test_target_env_steps_bit_for_bit_like_one_on_the_stock_env(target: str) -> None:
    """`make_env` of a target env against the same wrappers around the stock env: the target
    score and total (what sampling reads from `info`) are identical too."""
    spec = TARGETS[target]
    stock_class = PAIRS[spec.base][0]
    kwargs = {} if spec.base == "HalfCheetah" else {"terminate_when_unhealthy": False}
    stock = TimeLimit(
        TargetScoreInfo(FastMujocoRendering(stock_class(**kwargs), tracked_body="torso"), spec),
        LIMIT,
    )
    lean = make_env(spec.env)
    lean = TimeLimit(lean, LIMIT)  # a shorter limit inside ours: episodes end by truncation
    assert isinstance(lean.unwrapped, PAIRS[spec.base][1])
    assert _side_by_side(stock, lean, seed=3)["truncated"] >= 1
    lean.close()


@pytest.mark.parametrize("name", PAIRS)
def test_make_env_uses_the_lean_env(name: str) -> None:
    env = make_env(name)
    assert isinstance(env.unwrapped, PAIRS[name][1])
    env.close()


def test_lean_env_rejects_a_wrong_action_shape() -> None:
    env = LeanHopperEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="Action dimension mismatch"):
        env.step(np.zeros(4))
