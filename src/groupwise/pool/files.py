"""A published pool's directory: what `pool.publish.publish_pool` writes and the app reads.

Directory layout (``format: groupwise.behaviour.pool/1``)::

    pool.json         manifest: config (sampling and `PublishConfig`), metadata (policy,
                      seed), env, counts, frame_size [width, height], file names,
                      "length" (L) and "fps", and under "clip" the clips' timing
                      (`ClipTiming.as_json`): steps (L), stride (a frame every k-th
                      step), frames (⌈L / k⌉), fps, seconds (L · dt, simulated and
                      played), speed (1.0: real time), step_seconds (dt)
    behaviours.json   per behaviour: id ("b<i>", as in the tree), index, key, episode, start,
                      reset_seed, true_return, clip id, poster id
    behaviours.npz    obs (N, L, obs_dim), acts (N, L, act_dim), actions (N, L, *act_shape)
                      raw, true_rewards (N, L), episode, start, reset_seed (N,)
    predictions.npz   predicted_returns (N, K) of the ensemble that chose the pool, and
                      step_variance (N,) when known
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

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from groupwise.behaviour import BehaviourTree, TreeNode, to_json
from groupwise.behaviour.pool import BehaviourPool
from groupwise.clips.replay import episode_arrays
from groupwise.clips.store import ClipStore
from groupwise.clips.timing import ClipTiming
from groupwise.episodes.fragments import Fragment
from groupwise.episodes.ids import behaviour_id
from groupwise.types import FloatArray, IntArray

FORMAT = "groupwise.behaviour.pool/1"


@dataclass(frozen=True)
class PoolTimings:
    """Seconds per phase. Wall times of the parent, except the worker sums (see below)."""

    sample_s: float  # sampling episodes and cutting windows
    clips_s: float  # from handing jobs to the workers until the last clip is stored
    features_s: float  # kept for the format: features are part of dtw_s now
    dtw_s: float  # DTW distance matrix (overlaps clips_s)
    tree_s: float  # tree, group candidates, medoids (overlaps clips_s)
    write_s: float  # writing the directory
    total_s: float  # the whole call, wall time
    render_s: float  # worker-seconds in env.render(), summed over workers
    encode_s: float  # worker-seconds handing frames to ffmpeg, posters, storing, summed
    ffmpeg_cpu_s: float  # CPU seconds of the ffmpeg processes (they run beside the workers)
    replay_s: float  # worker-seconds stepping and checking replays, summed over workers
    workers: int
    behaviours: int
    frames: int  # frames rendered (N × ⌈L / k⌉; N posters when clips are rendered on demand)


@dataclass(frozen=True)
class PreparedPool:
    """A prepared pool (also written to `directory`, see the module docstring)."""

    directory: Path
    store: ClipStore
    fragments: tuple[Fragment, ...]  # (N,) in behaviour-index order
    clips: tuple[str, ...]  # (N,) clip-store id of each behaviour's MP4
    posters: tuple[str, ...]  # (N,) clip-store id of each behaviour's poster
    distances: FloatArray  # (N (N - 1) / 2,) condensed DTW distances
    tree: BehaviourTree
    candidates: tuple[TreeNode, ...]
    timings: PoolTimings
    timing: ClipTiming  # steps per behaviour, frame stride, fps, seconds


def write_pool(
    pool: PreparedPool,
    sampled: BehaviourPool,
    representatives: Mapping[str, tuple[int, ...]],
    config: Mapping[str, Any],
    metadata: Mapping[str, Any],
) -> None:
    """Write the directory of a published pool (module docstring); `config` is how it was
    sampled (size, length, oversample, exploration_fraction) and the `PublishConfig` it was
    published with, as JSON (its "width" and "height" give the manifest's frame size)."""
    trajectories = list(sampled.episodes)
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
        **({} if sampled.sources is None else {"source": sampled.sources}),  # type: ignore[arg-type]
    )
    predictions = {"predicted_returns": sampled.predicted_returns}
    if sampled.step_variance is not None:
        predictions["step_variance"] = sampled.step_variance
    # numpy's stub: **kwds may hit allow_pickle (a bool), so a dict of arrays fails to type
    np.savez(out / "predictions.npz", **predictions)  # type: ignore[arg-type]
    np.savez(out / "episodes.npz", **episode_arrays(trajectories))  # type: ignore[arg-type]  # as above
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
        "env": config["env"],
        "behaviours": len(fragments),
        "episodes": len(trajectories),
        "length": pool.timing.steps,
        "fps": round(pool.timing.fps, 6),
        "clip": pool.timing.as_json(),
        "frame_size": [config["width"], config["height"]],
        "store": _relative(pool.store.root, out),
        "config": dict(config),
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


def load_pool(directory: Path, round_index: int) -> BehaviourPool:
    """The pool published in `directory` (without its episodes); a pool written before
    predictions were kept has an ensemble of none (predicted returns (N, 0))."""
    fragments = load_fragments(directory)
    predicted, step_variance = np.zeros((len(fragments), 0)), None
    if (directory / "predictions.npz").is_file():
        with np.load(directory / "predictions.npz") as data:
            predicted = data["predicted_returns"]
            step_variance = data["step_variance"] if "step_variance" in data else None
    return BehaviourPool(
        round_index, fragments, predicted, step_variance, sources=load_sources(directory)
    )


def load_sources(directory: Path) -> IntArray | None:
    """Which source played each behaviour of a pool written by `prepare_pool`
    (`BehaviourPool.sources`); None for a pool written before they were kept."""
    with np.load(directory / "behaviours.npz") as data:
        return data["source"] if "source" in data else None


def _relative(path: Path, base: Path) -> str:
    try:
        return str(path.resolve().relative_to(base.resolve()))
    except ValueError:
        return str(path.resolve())


def write_json(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    tmp.replace(path)
