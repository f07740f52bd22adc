"""A published pool's directory: what `prepare.publish_pool` writes and the app reads.

Directory layout (``format: groupwise.pool/1``)::

    pool.json         manifest: config, metadata (policy, seed), env, counts, file names,
                      "length" (L) and "fps", and under "clip" the clips' timing
                      (`ClipTiming.as_json`): steps (L), stride (a frame every k-th
                      step), frames (⌈L / k⌉), fps, seconds (L · dt, simulated and
                      played), speed (1.0: real time), step_seconds (dt)
    behaviours.json   per behaviour: id ("b<i>", as in the tree), index, key, episode, start,
                      reset_seed, true_return, clip id, poster id
    behaviours.npz    obs (N, L, obs_dim), acts (N, L, act_dim), actions (N, L, *act_shape)
                      raw, true_rewards (N, L), episode, start, reset_seed (N,)
    episodes.npz      episode, reset_seed, length (E,), actions (E, T, *act_shape) padded
                      with zeros after each episode's `length` steps: enough to replay
                      (re-render) any window of the sampled episodes
    distances.npy     condensed DTW distances (N (N - 1) / 2,)
    tree.json         `behaviour.to_json` with leaf extras {"clip": id, "poster": id}
    candidates.json   group candidates: node id, level, size, leaves, medoids
    medoids.json      node id → up to `medoids` representative behaviours, for every inner node
    timings.json      `PoolTimings`
    clips/            the clip store (unless another store is passed in)
"""

import dataclasses
import json
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from groupwise.behaviour import to_json
from groupwise.clips.replay import episode_arrays
from groupwise.fragments import Fragment, Trajectory
from groupwise.pool import behaviour_id

if TYPE_CHECKING:
    from groupwise.prepare import PoolConfig, PreparedPool

FORMAT = "groupwise.pool/1"


def write_pool(
    pool: "PreparedPool",
    trajectories: list[Trajectory],
    representatives: Mapping[str, tuple[int, ...]],
    cfg: "PoolConfig",
    metadata: Mapping[str, Any],
) -> None:
    out, fragments = pool.directory, pool.fragments
    by_episode = {t.episode: t for t in trajectories}
    raw = np.stack([by_episode[f.episode].actions[f.start : f.start + f.length] for f in fragments])
    np.savez(
        out / "behaviours.npz",
        obs=np.stack([f.obs for f in fragments]),
        acts=np.stack([f.acts for f in fragments]),
        actions=raw,
        true_rewards=np.stack([f.true_rewards for f in fragments]),
        episode=np.array([f.episode for f in fragments]),
        start=np.array([f.start for f in fragments]),
        reset_seed=np.array([f.reset_seed for f in fragments]),
    )
    np.savez(out / "episodes.npz", **episode_arrays(trajectories))  # type: ignore[arg-type]
    np.save(out / "distances.npy", pool.distances)
    behaviours = [
        {
            "id": behaviour_id(i),
            "index": i,
            "key": f.key,
            "episode": f.episode,
            "start": f.start,
            "reset_seed": f.reset_seed,
            "true_return": f.true_return,
            "clip": pool.clips[i],
            "poster": pool.posters[i],
        }
        for i, f in enumerate(fragments)
    ]
    write_json(out / "behaviours.json", {"format": FORMAT, "behaviours": behaviours})
    extra = {i: {"clip": pool.clips[i], "poster": pool.posters[i]} for i in range(len(fragments))}
    write_json(out / "tree.json", to_json(pool.tree, leaf_extra=extra))
    candidates = [
        {
            "id": node.id,
            "level": node.level,
            "size": node.size,
            "leaves": list(node.leaves),
            "medoids": list(representatives[node.id]),
        }
        for node in pool.candidates
    ]
    write_json(out / "candidates.json", {"format": FORMAT, "candidates": candidates})
    write_json(out / "medoids.json", {k: list(v) for k, v in representatives.items()})
    manifest = {
        "format": FORMAT,
        "env": cfg.env,
        "behaviours": len(fragments),
        "episodes": len(trajectories),
        "length": pool.timing.steps,
        "fps": round(pool.timing.fps, 6),
        "clip": pool.timing.as_json(),
        "frame_size": [cfg.width, cfg.height],
        "store": _relative(pool.store.root, out),
        "config": dataclasses.asdict(cfg),
        "metadata": dict(metadata),
    }
    write_json(out / "pool.json", manifest)


def load_fragments(directory: Path) -> tuple[Fragment, ...]:
    """The fragments of a pool written by `prepare_pool`, in behaviour-index order."""
    with np.load(directory / "behaviours.npz") as data:
        return tuple(
            Fragment(
                obs=data["obs"][i],
                acts=data["acts"][i],
                true_rewards=data["true_rewards"][i],
                episode=int(data["episode"][i]),
                start=int(data["start"][i]),
                reset_seed=int(data["reset_seed"][i]),
            )
            for i in range(len(data["start"]))
        )


def _relative(path: Path, base: Path) -> str:
    try:
        return str(path.resolve().relative_to(base.resolve()))
    except ValueError:
        return str(path.resolve())


def write_json(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    tmp.replace(path)
