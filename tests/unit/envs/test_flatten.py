"""Dict and Tuple observations become one vector in the documented order; spaces that cannot
be taught are refused in one line (issue 42)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from tests.observation_envs import HORIZON, env_name

from groupwise.envs import horizon, make_env
from groupwise.envs.flatten import flat_layout
from groupwise.envs.spaces import observation_refusal


def test_a_dict_observation_is_flattened_in_sorted_key_order() -> None:
    env = make_env(env_name("DictObs-v0"))
    assert [leaf.name for leaf in env.leaves] == ["['height']", "['position']", "['velocity']"]
    assert [(leaf.start, leaf.size) for leaf in env.leaves] == [(0, 1), (1, 2), (3, 3)]
    assert env.observation_space == gym.spaces.Box(-np.inf, np.inf, (6,), np.float32)
    obs, _ = env.reset(seed=3)
    base = obs[0] - 100.0  # the env's per-episode offset
    expected = base + np.array([100.0, 200.0, 201.0, 300.0, 301.0, 302.0])
    np.testing.assert_allclose(obs, expected, rtol=1e-6)
    assert obs.dtype == np.float32
    assert horizon(env_name("DictObs-v0")) == HORIZON


def test_a_dict_holding_a_tuple_is_flattened_depth_first_with_its_bounds() -> None:
    env = make_env(env_name("NestedObs-v0"))
    assert [leaf.path for leaf in env.leaves] == [("arm", 0), ("arm", 1), ("base",)]
    np.testing.assert_array_equal(env.observation_space.low, [-20, -20, 0, -9, -9, -9])
    np.testing.assert_array_equal(env.observation_space.high, [20, 20, 50, 9, 9, 9])
    obs, _ = env.reset(seed=0)
    obs = env.step(np.zeros(2, np.float32))[0]  # step 1: every value + 0.01
    base = obs[3] - 0.01
    expected = base + 0.01 + np.array([10.0, 11.0, 20.0, 0.0, 1.0, 2.0])
    np.testing.assert_allclose(obs, expected, rtol=1e-6)


ROOT = Path(__file__).resolve().parents[3]
_PROBE = """
import json, numpy as np
from tests.observation_envs import env_name
from groupwise.envs import make_env
env = make_env(env_name("DictObs-v0"))
obs = [env.reset(seed=11)[0]] + [env.step(np.full(2, 0.5, np.float32))[0] for _ in range(3)]
print(json.dumps({"layout": [leaf.name for leaf in env.leaves],
                  "obs": np.stack(obs).tolist()}))
"""


def test_the_flat_order_is_the_same_in_processes_with_other_hash_seeds() -> None:
    """DictObs-v0 builds its dict from a set, whose order follows the hash seed."""
    runs = []
    for hash_seed in ("1", "2", "3"):
        result = subprocess.run(
            [sys.executable, "-c", _PROBE],
            capture_output=True,
            text=True,
            check=True,
            timeout=120,
            cwd=ROOT,  # where `tests` is a package
            env={**os.environ, "PYTHONHASHSEED": hash_seed, "PYTHONWARNINGS": "ignore"},
        )
        runs.append(json.loads(result.stdout.splitlines()[-1]))
    assert runs[0]["layout"] == ["['height']", "['position']", "['velocity']"]
    for run in runs[1:]:
        assert run == runs[0]
    first = np.array(runs[0]["obs"])
    assert first.shape == (4, 6)
    np.testing.assert_allclose(first[:, 1] - first[:, 0], 100.0, rtol=1e-5)  # position after height


@pytest.mark.parametrize(
    ("gym_id", "reason"),
    [
        ("ImageObs-v0", "its observation is an image, Box(32, 32, 3) of uint8"),
        ("PixelsAndStateObs-v0", "its observation at ['pixels'] is an image"),
        ("DiscreteObs-v0", "its observation is Discrete (Discrete(5))"),
        ("TextObs-v0", "its observation is Text"),
    ],
)
def test_observations_that_cannot_be_taught_are_refused_in_one_line(
    gym_id: str, reason: str
) -> None:
    with pytest.raises(ValueError) as caught:
        make_env(env_name(gym_id))
    message = str(caught.value)
    assert message.startswith(f"env {env_name(gym_id)} cannot be taught here: {reason}")
    assert "\n" not in message


def test_which_spaces_are_refused() -> None:
    box = gym.spaces.Box(-1.0, 1.0, (3,))
    assert observation_refusal(box) is None
    assert observation_refusal(gym.spaces.Box(-1.0, 1.0, (4, 3))) is None  # a matrix of numbers
    grey = gym.spaces.Box(0, 255, (8, 8), np.uint8)
    assert "image" in (observation_refusal(grey) or "")
    assert "bool" in (observation_refusal(gym.spaces.Box(0, 1, (3,), np.bool_)) or "")
    assert "empty Dict" in (observation_refusal(gym.spaces.Dict({})) or "")
    nested = gym.spaces.Tuple((box, gym.spaces.Dict({"n": gym.spaces.MultiDiscrete([2, 2])})))
    assert "at [1]['n'] is MultiDiscrete" in (observation_refusal(nested) or "")
    with pytest.raises(ValueError, match="Discrete"):
        flat_layout(gym.spaces.Discrete(3))
