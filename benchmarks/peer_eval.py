"""The peer benchmark's evaluation, the same code on both sides (each side's cell imports it in
its own venv, so it needs nothing but NumPy)."""

from collections.abc import Callable
from typing import Any

import numpy as np


def episode_returns(
    act: Callable[[np.ndarray], np.ndarray], make: Callable[[], Any], seeds: list[int]
) -> list[float]:
    """The true return of one deterministic episode per reset seed; `act` maps one batched
    observation (1, obs_dim) to one batched action (1, ...)."""
    returns = []
    for seed in seeds:
        env = make()
        obs, _ = env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            action = act(np.asarray(obs, dtype=np.float32)[None])[0]
            obs, reward, terminated, truncated, info = env.step(action)
            total += float(info.get("true_reward", reward))
            done = terminated or truncated
        env.close()
        returns.append(total)
    return returns
