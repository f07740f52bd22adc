"""Round checkpoints: everything a session needs to continue after a crash (SPEC §3).

Layout of one checkpoint directory (`<out>/checkpoints/round-0003/`):

    policy.zip         SB3 PPO policy with its optimiser and step count
    vecnormalize.npz   PPO's observation / return normaliser
    reward.pt          the reward ensemble (a torch state dict)
    dataset.npz        the cumulative preference dataset
    state.json         the round index and the per-round records so far

A checkpoint is written into a temporary directory and renamed into place, so a process
killed mid-write leaves the previous checkpoint intact.
"""

import json
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

CHECKPOINTS = "checkpoints"
STATE_FILE = "state.json"
REWARD_FILE = "reward.pt"
DATASET_FILE = "dataset.npz"


def checkpoint_dir(out: Path, round_index: int) -> Path:
    return out / CHECKPOINTS / f"round-{round_index:04d}"


def write_checkpoint(
    out: Path, round_index: int, state: dict[str, Any], write_files: Callable[[Path], None]
) -> Path:
    """Atomically create the checkpoint of `round_index`: `write_files(tmp_dir)` then rename."""
    final = checkpoint_dir(out, round_index)
    tmp = final.with_name(final.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    write_files(tmp)
    (tmp / STATE_FILE).write_text(json.dumps(state, indent=1))
    _fsync_dir(tmp)
    if final.exists():
        shutil.rmtree(final)
    os.replace(tmp, final)
    _fsync_dir(final.parent)
    return final


def latest_checkpoint(out: Path) -> tuple[Path, dict[str, Any]] | None:
    """The newest complete checkpoint under `out` and its state, or None if there is none."""
    root = out / CHECKPOINTS
    if not root.is_dir():
        return None
    done = sorted(p for p in root.glob("round-*") if not p.name.endswith(".tmp"))
    for path in reversed(done):
        state_file = path / STATE_FILE
        if state_file.is_file():
            return path, json.loads(state_file.read_text())
    return None


def _fsync_dir(path: Path) -> None:
    for child in path.iterdir():
        if child.is_file():
            with open(child, "rb") as handle:
                os.fsync(handle.fileno())
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
