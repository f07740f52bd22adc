"""Benchmark: preparing a behaviour pool (SPEC §3.1-3.2, §4, §9): time per phase.

Prepares a pool of 200 Hopper behaviours (the env's clip duration, 1.5 s = 188 steps shown
as 47 frames at real speed; `--length 30` for the study's L; random policy, 240×240 clips, 2
render workers) into a temporary directory with `groupwise.pool.publish.prepare_pool` and prints a
Markdown table. Render and encode run inside the workers, overlapping each other (a job's
ffmpeg encodes while its worker renders the next window) and the parent's features, DTW and
tree: their rows give worker-seconds (ffmpeg: CPU seconds) and the clip phase's wall time split
in proportion to them. The CPU time of all processes is printed too: unlike wall time, it
hardly changes when other processes compete for the cores.
Target: total ≤ 20 s on a 2-core machine.

    python benchmarks/pool_prep.py [--env Hopper] [--n 200] [--length L | --seconds S]
                                   [--oversample 1] [--repeats 1] [--workers 2]
"""

import argparse
import os
import resource
import statistics
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from groupwise.clips.timing import env_clip_timing
from groupwise.envs.rendering import ensure_gl_backend
from groupwise.pool.publish import PoolTimings, PublishConfig, prepare_pool
from groupwise.rl.policy_files import load_policy


def _cpu_seconds() -> float:
    """CPU time of this process and of its finished children (workers, with their ffmpeg)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def run_once(
    cfg: PublishConfig, size: int, length: int, oversample: float, seed: int
) -> tuple[PoolTimings, float]:
    """Prepare one pool of `size` behaviours of `length` steps (from `oversample` × `size`
    windows) in a fresh temporary directory; its timings and the CPU seconds of every
    process involved (the pool's workers have exited when it returns)."""
    with tempfile.TemporaryDirectory() as out:
        before = _cpu_seconds()
        pool = prepare_pool(
            cfg,
            load_policy("random", cfg.env),
            np.random.default_rng(seed),
            Path(out),
            size=size,
            length=length,
            oversample=oversample,
            show_progress=False,
        )
        cpu = _cpu_seconds() - before
    return pool.timings, cpu


def table(t: PoolTimings) -> str:
    """The Markdown table of one run."""
    render_cpu = t.render_s + t.replay_s
    encode_cpu = t.ffmpeg_cpu_s
    total_cpu = render_cpu + encode_cpu
    render_wall = t.clips_s * render_cpu / total_cpu if total_cpu > 0 else 0.0
    rows = [
        ("sample", f"{t.sample_s:.2f}", "", "episodes from the policy, cut into windows"),
        (
            "render",
            f"{render_wall:.2f}",
            f"{t.render_s:.1f} + {t.replay_s:.1f}",
            f"env.render() + replay steps, summed over workers (wall, so it grows when "
            f"other processes compete); {t.frames / t.render_s:.0f} frames per worker-second",
        ),
        (
            "encode",
            f"{t.clips_s - render_wall:.2f}",
            f"{t.ffmpeg_cpu_s:.1f}",
            f"CPU s of ffmpeg, which runs beside the workers (they spent {t.encode_s:.1f} s "
            "feeding it, on posters and the store)",
        ),
        ("features", f"{t.features_s:.3f}", "", "parent, while workers render"),
        ("DTW", f"{t.dtw_s:.3f}", "", "parent, while workers render (incl. numba cache load)"),
        ("tree", f"{t.tree_s:.3f}", "", "tree, candidates, medoids; parent, while workers render"),
        ("write", f"{t.write_s:.3f}", "", "arrays, JSON"),
        ("**total**", f"**{t.total_s:.2f}**", "", "wall time of prepare_pool"),
    ]
    lines = [
        "| phase | wall s | worker s | note |",
        "|---|---:|---:|---|",
        *(f"| {a} | {b} | {c} | {d} |" for a, b, c, d in rows),
        "",
        f"Render and encode overlap (clip phase {t.clips_s:.2f} s wall, split in proportion "
        "to their seconds); features, DTW and tree overlap them too.",
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--env", default="Hopper")
    parser.add_argument("--n", type=int, default=200, help="behaviours in the pool")
    parser.add_argument("--length", type=int, help="steps per behaviour (default: --seconds)")
    parser.add_argument("--seconds", type=float, help="simulated seconds (default: the env's)")
    parser.add_argument(
        "--oversample", type=float, default=1.0, help="windows sampled per kept one (app: 2)"
    )
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=1, help="runs; the median is shown")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args([] if argv is None else list(argv))
    backend = ensure_gl_backend()
    clip = env_clip_timing(args.env, args.seconds, steps=args.length)
    cfg = PublishConfig(env=args.env, workers=args.workers)
    load_before = os.getloadavg()[0]
    runs = [
        run_once(cfg, args.n, clip.steps, args.oversample, args.seed + k)
        for k in range(args.repeats)
    ]
    load_after = os.getloadavg()[0]
    median = statistics.median(t.total_s for t, _ in runs)
    shown, cpu = min(runs, key=lambda run: abs(run[0].total_s - median))
    print(
        f"Pool preparation: {args.n} {args.env} behaviours × {clip.steps} steps "
        f"({clip.seconds:.2f} s; clips of {clip.frames} frames, every {clip.stride}. step, "
        f"{clip.fps:.4g} fps), {args.oversample:g}× windows sampled, random "
        f"policy, {cfg.width}×{cfg.height}, x264 {cfg.video.preset}, {cfg.workers} workers, "
        f"{os.cpu_count()} CPUs, MUJOCO_GL={backend}; load average {load_before:.1f} before, "
        f"{load_after:.1f} after.\n"
    )
    print(table(shown))
    cores = os.cpu_count() or 1
    print(
        f"\nCPU time of all processes (parent, workers, ffmpeg): {cpu:.1f} s, i.e. at least "
        f"{cpu / cores:.1f} s of wall time on {cores} otherwise idle cores."
    )
    if len(runs) > 1:
        totals = ", ".join(f"{t.total_s:.1f} (CPU {c:.1f})" for t, c in runs)
        print(f"Totals of {len(runs)} runs, wall (CPU) s: {totals}; the median run is shown.")


if __name__ == "__main__":
    main(sys.argv[1:])
