"""Benchmark: a round on screen (issue 22): preparing a pool as the app's worker does, phase by
phase, and how long a clip rendered on demand takes to reach the page.

For each window length (30 steps, the study's L, and the env's default clip, 1.5 s = 188
Hopper steps) and each pool size, the app's round 0 (`SessionSettings` defaults, random
policy, a fresh reward ensemble): `sample_pool` (2 N windows, at most 1,000 or N:
`LoopConfig.pool_windows_max`; the ensemble's most uncertain kept), DTW in the tree
config's band, the tree, the Groupwise-DM's suggestions
(`worker.job.session_strategy`, 2× the comparison budget), then `publish_pool` — with clips
on demand (the app's default) a poster per behaviour and each clip's recipe; with
``--clips eager`` every clip as before — and the round's rows (`worker.offers`). The
render workers are started and the DTW kernels compiled before the clock starts, as in the
long-lived worker; DTW runs on the idle cores, as in the worker's prepare job.

Sampling steps its envs on the free cores (`rl.batch_envs`; `--sample-processes P` fixes
the number, 1: in this process only, as before); the pool is the same either way.

Per phase: wall s, CPU s of every process (this one with its threads, the render workers and
the sampling helpers), the CPU floor on this machine (CPU s / cores: the wall time if the
phase's work were spread over every core) and wall / floor (2 on 2 cores: one core busy).
"on screen" is their sum: from sampling to the round's rows, when the page can show
posters, tree and suggestions.

Then the first-frame budget of clips on demand: a real server (`create_app`, no worker) on
the pool's store; request → first byte of a clip not rendered yet, one at a time (p50 / p95
after the render processes are warm, and the very first with their start), and a group of 8
asked at once (the comparison view), the last first byte.

    python -m benchmarks.pool_prep [--env Hopper] [--n 200 [1000]] [--lengths 30 default]
                                   [--clips on_demand|eager] [--workers 2] [--clip-requests 20]
                                   [--sample-processes P]
"""

import argparse
import contextlib
import os
import resource
import socket
import statistics
import sys
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from groupwise.behaviour import kernel_threads
from groupwise.behaviour import warm_up as warm_up_dtw
from groupwise.clips.render import RenderPool
from groupwise.clips.replay import FrameSettings
from groupwise.clips.store import ClipStore
from groupwise.config import LoopConfig
from groupwise.envs import make_env
from groupwise.envs.rendering import ensure_gl_backend
from groupwise.pool.publish import PreparedPool, publish_pool
from groupwise.pool.sampling import sample_pool
from groupwise.reward import RewardEnsemble
from groupwise.rl.batch_envs import free_cores
from groupwise.rl.policy_files import load_policy
from groupwise.storage import SessionSettings
from groupwise.worker.job import offered_queries, session_strategy
from groupwise.worker.offers import prepared_round
from groupwise.worker.publishing import publish_config

GOALS = {200: 8.0, 1000: 30.0}
"""Wall seconds to a round on screen on 2 cores, by pool size (issue 22)."""


def _clock_ticks() -> int:
    return os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def cpu_seconds() -> float:
    """CPU time of this process (all threads), of its finished children, and of its live
    descendants (the render workers; read from /proc where there is one)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    done = resource.getrusage(resource.RUSAGE_CHILDREN)
    total = own.ru_utime + own.ru_stime + done.ru_utime + done.ru_stime
    return total + sum(_proc_cpu(pid) for pid in _descendants(os.getpid()))


def _descendants(root: int) -> list[int]:
    parents: dict[int, int] = {}
    for entry in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, ValueError, IndexError):
            fields = entry.read_text().rsplit(")", 1)[1].split()
            parents[int(entry.parent.name)] = int(fields[1])
    found, frontier = [], [root]
    while frontier:
        parent = frontier.pop()
        children = [pid for pid, ppid in parents.items() if ppid == parent]
        found += children
        frontier += children
    return found


def _proc_cpu(pid: int) -> float:
    """utime + stime + cutime + cstime of a live process, in seconds (0 when gone)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return 0.0
    return sum(int(f) for f in fields[11:15]) / _clock_ticks()


@dataclass
class Phase:
    name: str
    wall_s: float
    cpu_s: float
    load: float


@dataclass
class Run:
    """One pool prepared: its phases, and the on-demand first-frame times."""

    n: int
    steps: int
    frames: int
    phases: list[Phase] = field(default_factory=list)
    first_clip_s: float = float("nan")  # the first clip asked for, render processes cold
    ttfb_s: list[float] = field(default_factory=list)  # cold clips one at a time, warm workers
    group_s: float = float("nan")  # 8 clips asked at once: the last first byte

    @contextlib.contextmanager
    def phase(self, name: str) -> Iterator[None]:
        wall, cpu = time.perf_counter(), cpu_seconds()
        yield
        wall_s, cpu_s = time.perf_counter() - wall, cpu_seconds() - cpu
        self.phases.append(Phase(name, wall_s, cpu_s, os.getloadavg()[0]))


def prepare(
    env: str,
    n: int,
    settings: SessionSettings,
    mode: Literal["on_demand", "eager"],
    render: RenderPool,
    out: Path,
    seed: int,
    processes: int | None = None,
    windows_max: int | None = LoopConfig.pool_windows_max,
) -> tuple[Run, PreparedPool]:
    """Round 0 of a session with `settings`, as the worker prepares it (module docstring)."""
    cfg = settings.run_config(env)
    loop = cfg.loop
    rng = np.random.default_rng(seed)
    ensemble = RewardEnsemble.for_env(lambda: make_env(env), cfg.reward, rng)
    policy = load_policy("random", env)
    timing = settings.clip_timing(env)
    run = Run(n, timing.steps, timing.frames)
    with run.phase("sample"):
        pool = sample_pool(
            lambda: make_env(env), policy, n, loop.fragment_length, rng,
            exploration_fraction=loop.exploration_fraction, oversample=loop.pool_oversample,
            max_windows=windows_max,
            ensemble=ensemble, select=loop.pool_selection, processes=processes,
        )  # fmt: skip
    with run.phase("DTW"), kernel_threads(free_cores()):
        pool.measure_distances(cfg=cfg.tree)
    with run.phase("tree"):
        pool.tree(cfg.tree)
    with run.phase("suggestions"):
        queries = session_strategy(cfg, "groupwise").propose(pool, offered_queries(settings), rng)
    publish = replace(publish_config(cfg, settings.frame_size, render.workers), clips=mode)
    with run.phase("posters" if mode == "on_demand" else "clips"):
        published = publish_pool(
            publish, pool, out, store=ClipStore(out / "clips"), render_pool=render,
            show_progress=False,
        )  # fmt: skip
    with run.phase("rows"):
        prepared_round(pool, published, queries, settings.suggestions)
    return run, published


@contextlib.contextmanager
def clip_server(data_dir: Path) -> Iterator[str]:
    """A real app (no worker) on `data_dir`'s clip store, on a free port; its base URL."""
    import uvicorn

    from groupwise.server import AppConfig, create_app

    app = create_app(AppConfig(data_dir=data_dir, start_worker=False))
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    sock.bind(("127.0.0.1", 0))
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", access_log=False))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    while not server.started:
        time.sleep(0.01)
    try:
        yield f"http://127.0.0.1:{sock.getsockname()[1]}"
    finally:
        server.should_exit = True
        thread.join(10)


def first_byte_s(client: Any, url: str) -> float:
    """Seconds from sending a GET to its first body byte (the clip's status checked)."""
    start = time.perf_counter()
    with client.stream("GET", url) as response:
        if response.status_code != 200:
            raise RuntimeError(f"GET {url}: {response.status_code} {response.read()[:200]!r}")
        for _ in response.iter_raw(1):
            break
        return time.perf_counter() - start


def measure_on_demand(run: Run, published: PreparedPool, data_dir: Path, requests: int) -> None:
    """First-frame budget of `published`'s clips through a real server (module docstring)."""
    import httpx

    clips = list(published.clips)
    with clip_server(data_dir) as base, httpx.Client(base_url=base, timeout=120) as client:
        run.first_clip_s = first_byte_s(client, f"/clips/{clips[0]}")
        first_byte_s(client, f"/clips/{published.posters[1]}")  # a poster: warms the workers
        time.sleep(2.0)
        for clip in clips[1 : 1 + requests]:
            run.ttfb_s.append(first_byte_s(client, f"/clips/{clip}"))
        group = clips[1 + requests : 9 + requests]
        times: list[float] = []
        threads = [
            threading.Thread(target=lambda c=c: times.append(first_byte_s(client, f"/clips/{c}")))
            for c in group
        ]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        run.group_s = max(times) if times else float("nan")


def settle(timeout_s: float = 15.0) -> None:
    """Wait until every core is idle (at most `timeout_s`): a render worker that lost the
    race for the warm-up jobs may still be importing, and sampling, which asks `free_cores`
    how many processes to step in, would then take one core for the whole pool."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
    deadline = time.monotonic() + timeout_s
    while free_cores(0.5) < cores and time.monotonic() < deadline:
        pass


def report(runs: Sequence[Run], env: str, mode: str, workers: int, windows_max: int | None) -> str:
    cores = os.cpu_count() or 1
    lines = [
        f"Pool preparation, {env}, random policy, a fresh ensemble (round 0), app settings "
        f"(N of max(N, min(2 N, {windows_max or '∞'})) windows sampled; 240×240, "
        f"{workers} render workers), clips {mode}; {cores} "
        f"CPUs, MUJOCO_GL={os.environ.get('MUJOCO_GL', '')}. floor = CPU s / {cores} cores; "
        "ratio = wall / floor. load: 1-min load average after the phase.",
        "",
        "| N | L (frames) | phase | wall s | CPU s | floor s | ratio | load |",
        "|---:|---|---|---:|---:|---:|---:|---:|",
    ]
    for run in runs:
        label = f"{run.steps} ({run.frames})"
        for p in run.phases:
            floor = p.cpu_s / cores
            ratio = p.wall_s / floor if floor > 0 else float("nan")
            lines.append(
                f"| {run.n} | {label} | {p.name} | {p.wall_s:.2f} | {p.cpu_s:.2f} | "
                f"{floor:.2f} | {ratio:.2f} | {p.load:.1f} |"
            )
        wall = sum(p.wall_s for p in run.phases)
        cpu = sum(p.cpu_s for p in run.phases)
        goal = GOALS.get(run.n)
        target = f" (goal ≤ {goal:g} s)" if goal and run.steps > 30 else ""
        load = max(p.load for p in run.phases)
        lines.append(
            f"| {run.n} | {label} | **on screen**{target} | **{wall:.2f}** | {cpu:.2f} | "
            f"{cpu / cores:.2f} | {wall / (cpu / cores):.2f} | {load:.1f} |"
        )
    if any(run.ttfb_s for run in runs):
        lines += [
            "",
            "Clips on demand through a real server, request → first byte of a clip not "
            "rendered yet (render processes of the server, warm unless said):",
            "",
            "| N | L (frames) | first clip, processes cold | p50 | p95 | clips "
            "| 8 at once, last | load |",
            "|---:|---|---:|---:|---:|---:|---:|---:|",
        ]
        for run in runs:
            if not run.ttfb_s:
                continue
            ms = sorted(t * 1e3 for t in run.ttfb_s)
            p95 = ms[min(len(ms) - 1, round(0.95 * (len(ms) - 1)))]
            lines.append(
                f"| {run.n} | {run.steps} ({run.frames}) | {run.first_clip_s * 1e3:.0f} ms | "
                f"{statistics.median(ms):.0f} ms | {p95:.0f} ms | {len(ms)} | "
                f"{run.group_s * 1e3:.0f} ms | {os.getloadavg()[0]:.1f} |"
            )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env", default="Hopper")
    parser.add_argument("--n", type=int, nargs="+", default=[200], help="pool sizes")
    parser.add_argument(
        "--lengths",
        nargs="+",
        default=["30", "default"],
        help="steps per behaviour, or 'default' (the env's clip seconds: Hopper 1.5 s)",
    )
    parser.add_argument("--clips", choices=["on_demand", "eager"], default="on_demand")
    parser.add_argument("--workers", type=int, default=2, help="render workers")
    parser.add_argument("--clip-requests", type=int, default=20, help="cold clips asked for")
    parser.add_argument(
        "--sample-processes",
        type=int,
        default=None,
        help="processes stepping the sampled envs (default: the free cores for large batches)",
    )
    parser.add_argument(
        "--windows-max",
        type=lambda text: None if text == "none" else int(text),
        default=LoopConfig.pool_windows_max,
        help="windows a pool is chosen from at most (LoopConfig.pool_windows_max; 'none': 2 N)",
    )
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args([] if argv is None else list(argv))
    ensure_gl_backend()
    warm_up_dtw()
    runs = []
    with RenderPool(args.workers) as render:
        render.warm_up(FrameSettings(args.env))  # the worker's pool is long-lived and warm
        render.start([], ClipStore(tempfile.mkdtemp())).wait(show_progress=False)
        for length in args.lengths:
            for n in args.n:
                steps = None if length == "default" else int(length)
                settings = SessionSettings(pool_size=n, fragment_length=steps).for_env(args.env)
                settle()  # as the long-lived worker's cores are when a round is asked for
                with tempfile.TemporaryDirectory() as tmp:
                    run, published = prepare(
                        args.env, n, settings, args.clips, render, Path(tmp), args.seed,
                        args.sample_processes, args.windows_max,
                    )  # fmt: skip
                    if args.clips == "on_demand" and args.clip_requests > 0:
                        measure_on_demand(run, published, Path(tmp), args.clip_requests)
                runs.append(run)
                print(f"[{n} × {run.steps} steps done]", file=sys.stderr, flush=True)
    print(report(runs, args.env, args.clips, args.workers, args.windows_max))


if __name__ == "__main__":
    main(sys.argv[1:])
