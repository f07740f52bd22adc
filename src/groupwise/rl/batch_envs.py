"""The envs of a sampling batch, stepped side by side in this process and in helper processes.

`rl.rollout` steps a batch of episodes in lock step: the policy sees one batched observation
per step and every random draw (reset seeds, the policy's actions, exploration) comes from
the caller's generator in this process. Only the envs' own work, the physics and the env's
Python around it, is spread: the batch's envs are cut into contiguous shards, the first
stepped here and each other one in a helper process that makes its envs with the same
factory (sent with cloudpickle). An env's episode depends only on its reset seed and
its actions, so every observation, reward and physics snapshot is bit for bit what the same
env stepped here would give, whatever the number of processes (tested: the same trajectories
and generator state with 1, 2 and 3).

A helper is a fresh interpreter (``python -m groupwise.rl.batch_envs``; not forked: numba's
OpenMP layer, used for DTW in the worker, kills forked children; not a multiprocessing
spawn child, which would import the parent's main module first) talking over a socket pair.
A helper answers about 0.8 s after it starts (0.4 CPU-seconds of imports), which is why
`processes_for` uses helpers only for batches of many steps, and only on cores other work
leaves free (`free_cores`); a factory that cannot be pickled falls back to stepping every
env here.
"""

import contextlib
import itertools
import logging
import math
import os
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import cloudpickle
import gymnasium as gym
import numpy as np

from groupwise.envs.physics_state import physics_state
from groupwise.envs.targets import TARGET_TOTAL_KEY
from groupwise.envs.true_reward import TRUE_REWARD_KEY
from groupwise.types import FloatArray

logger = logging.getLogger(__name__)

EnvFactory = Callable[[], gym.Env]

StepResult = tuple[Any, float, float, bool, FloatArray | None]
"""One env's step: (observation after it, true reward, the env's episode score so far (nan:
none), whether the episode ended (terminated or truncated), the physics state before the
step when a snapshot was asked for, else None)."""

PARALLEL_MIN_STEPS = 40_000
"""Env steps (episodes × their step limit) from which `processes_for` spreads a batch over
the cores: a helper's start (about 0.4 CPU-seconds of imports) is then a few per cent of the
work (a Hopper step is about 0.2 ms with its Python)."""


def processes_for(n_envs: int, limit: int, processes: int | None) -> int:
    """How many processes step a batch of `n_envs` envs of up to `limit` steps: `processes`
    when given (at most one per env); else 1 below `PARALLEL_MIN_STEPS` steps, and from
    there one per core that other work leaves free (`free_cores`)."""
    if processes is not None:
        if processes < 1:
            raise ValueError(f"processes must be >= 1 or None, got {processes}")
        return min(processes, n_envs)
    if n_envs * limit < PARALLEL_MIN_STEPS:
        return 1
    return max(1, min(free_cores(), n_envs))


def free_cores(sample_s: float = 0.2) -> int:
    """The cores this process may run on (its affinity) that are idle now, rounded, at least 1:
    the share of CPU time the whole machine spent idle over the next `sample_s` seconds
    (/proc/stat), while this process sleeps and so is not counted. Where there is no
    /proc/stat: the cores less the 1-minute load average, less 1 for this process.

    Helpers only pay where cores are idle: in lock step, a shard whose process waits for a
    core holds up every other one, and a helper costs 0.4 CPU-seconds of imports. On the
    shared 2-core machine at load 4 (another session's two processes) two processes sampled a
    200-behaviour Hopper pool in 14.8 s against 13.7 s for one (issue 22). The load average
    remembers a minute: the app's worker, just done preparing one session's pool on both
    cores, read load 1.8 and sampled the next, 1,000 behaviours, in one process (18 s
    against 13 s in two).
    """
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    cores = cores or 1
    before = _cpu_times()
    if before is not None:
        time.sleep(sample_s)
        after = _cpu_times()
        if after is not None:
            return max(1, min(cores, round(idle_cores(before, after))))
    busy = max(0.0, os.getloadavg()[0] - 1.0) if hasattr(os, "getloadavg") else 0.0
    return max(1, min(cores, round(cores - busy)))


def idle_cores(before: Sequence[int], after: Sequence[int]) -> float:
    """Cores idle between two readings of /proc/stat's per-CPU lines (`_cpu_times`): each
    CPU's idle and iowait share of its time in between, summed."""
    idle = 0.0
    for busy0, idle0, busy1, idle1 in zip(
        before[0::2], before[1::2], after[0::2], after[1::2], strict=True
    ):
        total = (busy1 - busy0) + (idle1 - idle0)
        idle += (idle1 - idle0) / total if total > 0 else 1.0
    return idle


def _cpu_times() -> list[int] | None:
    """Busy and idle jiffies of each CPU this process may run on, flattened ([busy0, idle0,
    busy1, idle1, ...]); None where /proc/stat cannot be read."""
    allowed = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None
    try:
        lines = Path("/proc/stat").read_text().splitlines()
    except OSError:
        return None
    times: list[int] = []
    for line in lines:
        name, *fields = line.split()
        if not name.startswith("cpu") or name == "cpu":
            continue
        if allowed is not None and int(name[3:]) not in allowed:
            continue
        values = [int(f) for f in fields[:8]]  # user nice system idle iowait irq softirq steal
        idle = values[3] + values[4]
        times += [sum(values) - idle, idle]
    return times or None


def step_envs(
    envs: Sequence[gym.Env], indices: Sequence[int], actions: Sequence[Any], snapshot: bool
) -> list[StepResult]:
    """Step `envs[i]` with each (i, action) of `indices` × `actions`; see `StepResult`."""
    results: list[StepResult] = []
    for i, action in zip(indices, actions, strict=True):
        state = physics_state(envs[i]) if snapshot else None
        after, reward, terminated, truncated, info = envs[i].step(action)
        results.append(
            (
                after,
                float(info.get(TRUE_REWARD_KEY, reward)),
                float(info.get(TARGET_TOTAL_KEY, math.nan)),
                bool(terminated or truncated),
                state,
            )
        )
    return results


class BatchEnvs:
    """`n` envs made by `make_env`, numbered 0 … n − 1, stepped across `processes` processes
    (this one and `processes` − 1 helpers; module docstring). Use as a context manager.

    Env 0 is always made here (`first`: the batch's action space and spec).
    """

    def __init__(self, make_env: EnvFactory, n: int, processes: int = 1) -> None:
        if n < 1 or processes < 1:
            raise ValueError(f"need n >= 1 and processes >= 1, got {n} and {processes}")
        bounds = np.linspace(0, n, min(processes, n) + 1).round().astype(int)
        self._helpers: list[_Helper] = []
        self._starts: list[int] = []
        if len(bounds) > 2:
            self._helpers = _start_helpers(make_env, bounds)  # they start while we make ours
            self._starts = [int(b) for b in bounds[1:-1]] if self._helpers else []
        here = self._starts[0] if self._starts else n
        self.n = n
        try:
            self.local = [make_env() for _ in range(here)]
        except BaseException:
            self.close()
            raise

    @property
    def processes(self) -> int:
        return 1 + len(self._helpers)

    @property
    def first(self) -> gym.Env:
        return self.local[0]

    def reset(self, seeds: Sequence[int]) -> list[Any]:
        """Reset env i with seed `seeds[i]`; the first observations, in env order."""
        for helper, (lo, hi) in zip(self._helpers, self._helper_ranges(), strict=True):
            helper.conn.send(("reset", [int(s) for s in seeds[lo:hi]]))
        first = [env.reset(seed=int(s))[0] for env, s in zip(self.local, seeds, strict=False)]
        for helper in self._helpers:
            first += helper.receive()
        return first

    def step(
        self, running: Sequence[int], actions: Sequence[Any], snapshot: bool
    ) -> list[StepResult]:
        """Step the envs `running` (ascending) with `actions` (one each), the physics state
        captured before the step where `snapshot`; their results in the same order."""
        ranges = self._helper_ranges()
        cuts = np.searchsorted(np.asarray(running), [lo for lo, _ in ranges]).tolist()
        cuts.append(len(running))
        for k, helper in enumerate(self._helpers):
            lo = ranges[k][0]
            part = slice(cuts[k], cuts[k + 1])
            helper.conn.send(("step", ([i - lo for i in running[part]], actions[part], snapshot)))
        here = cuts[0] if cuts else len(running)
        results = step_envs(self.local, running[:here], actions[:here], snapshot)
        for helper in self._helpers:
            results += helper.receive()
        return results

    def close(self) -> None:
        for env in getattr(self, "local", []):
            env.close()
        for helper in self._helpers:
            helper.close()
        self._helpers = []

    def __enter__(self) -> "BatchEnvs":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _helper_ranges(self) -> list[tuple[int, int]]:
        return list(zip(self._starts, [*self._starts[1:], self.n], strict=False))


class _Helper:
    """A helper process and this end of its socket."""

    def __init__(self, process: subprocess.Popen[bytes], conn: Connection) -> None:
        self.process = process
        self.conn = conn

    def receive(self) -> Any:
        try:
            status, value = self.conn.recv()
        except EOFError:
            code = self.process.poll()
            raise RuntimeError(f"an env helper process exited (status {code})") from None
        if status == "error":
            raise RuntimeError(f"an env helper process failed: {value}")
        return value

    def close(self) -> None:
        with contextlib.suppress(OSError, ValueError):
            self.conn.send(("close", None))
        try:
            self.process.wait(5)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self.conn.close()


def _start_helpers(make_env: EnvFactory, bounds: np.ndarray) -> list[_Helper]:
    """A helper per shard after the first, or none (stepping stays here) when the factory
    cannot be pickled.

    A helper is a fresh interpreter running this module (not a multiprocessing child: those
    import the parent's main module first, a benchmark's or the CLI's, seconds of imports
    it does not need), given this process's `sys.path` and the pickled factory.
    """
    try:
        factory = _pickled(make_env)
    except Exception as error:
        logger.info("stepping every env in this process: its factory does not pickle (%s)", error)
        return []
    helpers: list[_Helper] = []
    for lo, hi in itertools.pairwise(bounds[1:]):
        ours, theirs = socket.socketpair()
        process = subprocess.Popen(
            [sys.executable, "-m", "groupwise.rl.batch_envs", str(theirs.fileno())],
            pass_fds=[theirs.fileno()],
            env=_helper_env(),
        )
        theirs.close()
        conn = Connection(ours.detach())
        conn.send((sys.path, factory, int(hi - lo)))
        helpers.append(_Helper(process, conn))
    return helpers


def _helper_env() -> dict[str, str]:
    """This process's environment, with groupwise's own directory first on PYTHONPATH: the
    helper finds this copy of the package whatever put it on this process's path."""
    env = dict(os.environ)
    here = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (here, env.get("PYTHONPATH")) if p)
    return env


def _pickled(make_env: EnvFactory) -> bytes:
    """The factory pickled by cloudpickle: by value where it comes from outside groupwise (a
    script, a benchmark, a test module pytest loaded with ``--import-mode=importlib``: modules
    a fresh interpreter may not find by name); what it calls is imported by name."""
    name = getattr(make_env, "__module__", None) or "__main__"
    module = sys.modules.get(name)
    if module is None or name == "__main__" or name.partition(".")[0] == "groupwise":
        return cloudpickle.dumps(make_env)
    cloudpickle.register_pickle_by_value(module)
    try:
        return cloudpickle.dumps(make_env)
    finally:
        cloudpickle.unregister_pickle_by_value(module)


def _serve(conn: Connection) -> None:
    """A helper's loop: make its envs, then answer "reset" and "step" until "close"."""
    envs: list[gym.Env] = []
    failure = None
    try:
        path, factory, n = conn.recv()
        sys.path[:] = path
        make_env = cloudpickle.loads(factory)
        envs = [make_env() for _ in range(n)]
    except Exception as error:
        failure = repr(error)
    try:
        while True:
            command, payload = conn.recv()
            if command == "close":
                break
            try:
                if failure is not None:
                    raise RuntimeError(f"making the envs failed: {failure}")
                if command == "reset":
                    value: Any = [
                        env.reset(seed=s)[0] for env, s in zip(envs, payload, strict=True)
                    ]
                else:
                    value = step_envs(envs, *payload)
            except Exception as error:
                conn.send(("error", repr(error)))
                continue
            conn.send(("ok", value))
    except (EOFError, KeyboardInterrupt):
        pass
    finally:
        for env in envs:
            env.close()
        conn.close()


if __name__ == "__main__":
    _serve(Connection(socket.socket(fileno=int(sys.argv[1])).detach()))
