"""Small recorded datasets the tests build themselves, never download (issue 42)."""

import os
from pathlib import Path

import gymnasium as gym
import numpy as np

HOPPER = "Hopper-v5"


def build_hopper_dataset(
    root: Path, dataset_id: str, steps: int, seed: int = 0, **make_kwargs: object
) -> Path:
    """A Minari dataset of `steps` random-action steps of Hopper-v5 (made with `make_kwargs`,
    e.g. ``terminate_when_unhealthy=False``), recorded by Minari's own `DataCollector` (arrow
    format) into the Minari store `root` (MINARI_DATASETS_PATH is `root` meanwhile, then as
    it was). Episode 0 is the env reset with `seed`, then the actions of
    `np.random.default_rng(seed)`. Returns the dataset's directory (benchmarks/dataset_pool.py
    records its dataset with it too)."""
    from minari import DataCollector

    before = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(root)
    try:
        env = DataCollector(gym.make(HOPPER, **make_kwargs), data_format="arrow")
        rng = np.random.default_rng(seed)
        env.reset(seed=seed)
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 3).astype(np.float32))
            if terminated or truncated:
                env.reset()
        env.create_dataset(dataset_id=dataset_id, algorithm_name="random")
        env.close()
    finally:
        if before is None:
            del os.environ["MINARI_DATASETS_PATH"]
        else:
            os.environ["MINARI_DATASETS_PATH"] = before
    return root / dataset_id
