"""Small recorded datasets the tests build themselves, never download (issue 42)."""

from pathlib import Path

import gymnasium as gym
import numpy as np

HOPPER = "Hopper-v5"


def build_hopper_dataset(root: Path, dataset_id: str, steps: int, seed: int = 0) -> Path:
    """A Minari dataset of `steps` random-action steps of Hopper-v5, recorded by Minari's own
    `DataCollector` (arrow format) into the Minari store `root` (set MINARI_DATASETS_PATH to
    it first). Episode 0 is the env reset with `seed`, then the actions of
    `np.random.default_rng(seed)`. Returns the dataset's directory."""
    from minari import DataCollector

    env = DataCollector(gym.make(HOPPER), data_format="arrow")
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 3).astype(np.float32))
        if terminated or truncated:
            env.reset()
    env.create_dataset(dataset_id=dataset_id, algorithm_name="random")
    env.close()
    return root / dataset_id
