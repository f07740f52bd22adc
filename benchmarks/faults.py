"""Benchmark: kill the server or its training worker at random moments under load; nothing
answered may be lost, duplicated or half-stored, and the session must carry on.

Runs a real `groupwise serve` (uvicorn, the training worker) on a temporary data directory
and a database of its own (``--db``: SQLite in WAL mode in the data directory, a throw-away
local PostgreSQL cluster with fsync on, or an empty database at a URL; `benchmarks.database`)
with a tiny GridWorld session (rounds of 16 behaviours that prepare and train in seconds).
`clients` threads submit valid judgements over the open round's behaviours, each with its
own ``client_id``; a request that fails in transit (the server died) is sent again with the
same ``client_id`` until it gets an answer, so a judgement stored just before the kill is
answered 200 by the next server instead of stored twice.

Each trial waits until the session is usable again (the round open), sometimes ends the
round so that the worker trains and prepares the next one, lets the load run for a random
moment, and then SIGKILLs either the server (the harness starts a new one on the same data,
which resumes the session) or the worker (the server reports the step failed; the harness
asks for ``POST /retry``, as the page's button does). Every choice comes from one seeded
`np.random.Generator`. At the end it stops the server and reads the database itself, with
the same portable SQL on either backend (`fault_audit.audit`): every judgement answered 2xx
is stored exactly once, as sent, with its pairs; nothing is half-stored; no worker outlived
its server.

Recovery time: from the kill until the API answers again with the session not failed and,
when it is mid-step, a worker running it (a server restart dominates: importing the app).

    python -m benchmarks faults
    python -m benchmarks.faults [--trials 100] [--clients 4] [--seed 0] [--fuzz-cases 10000]
        [--training continuous|rounds] [--db sqlite|postgresql|URL]

After the trials it runs the schemathesis fuzz of the live API (`benchmarks.fuzz`, its own
server on SQLite whatever ``--db`` says) unless ``--fuzz-cases 0``.

Measured on 2 cores shared with other work (load average 9), seed 0, 4 clients: 100 kills
(43 of the server, 57 of the worker) in 25 min; 21,608 judgements sent, 4,855 answered 2xx
(35 of them on a resend, answered 200 with the judgement the killed server had committed),
4,855 stored; 0 lost, 0 duplicated, 0 half-stored, 0 altered, 0 5xx, 0 stuck, 0 orphan
workers. Median recovery 5.2 s after a server kill (a new process importing the app), 0.3 s
to a new worker after a worker kill; the round was open again after a median 5.3 s / 16.0 s
(the latter includes the ended round's training and the next round's preparation). Then
schemathesis: 10,395 requests over 21 operations, 0 5xx, 0 check failures. On PostgreSQL
(``--db postgresql``), 20 kills, twice, beside SQLite on the same schedule: nothing lost on
either, recovery the same (docs/results/faults-postgres.md).
"""

import argparse
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import numpy as np

from benchmarks.database import database
from benchmarks.fault_audit import Audit, Ledger, audit
from groupwise.storage import default_url

URL = re.compile(r"open (http://\S+?)/\?session=(s-[0-9a-f]+)")
POOL = 16
SETTINGS = {
    "recipe": "paper",  # the infrastructure as measured before: no pre-training, no variants
    "frame_size": 32,
    "render_workers": 0,
    "eval_episodes": 1,
    "ppo": {"n_envs": 1, "n_steps": 64, "batch_size": 32, "n_epochs": 1, "net_arch": [16]},
    "reward": {"epochs": 1, "initial_epoch_multiplier": 2},
}
FLAGS = [
    "--pool-size", str(POOL),
    "--fragment-length", "10",
    "--ppo-steps-per-round", "256",
    "--rounds", "100",
    "--round-seconds", "0",
    "--comparisons-per-round", "0",
]  # fmt: skip
"""A GridWorld session whose rounds prepare and train in seconds and never end by themselves."""
WORKER_DIED = "the training worker stopped"


@dataclass(frozen=True)
class FaultConfig:
    """One run of the harness."""

    trials: int = 100
    """Kills, each followed by a restart (server) or a retry (worker)."""
    clients: int = 4
    """Threads submitting judgements all the time."""
    seed: int = 0
    """Seeds every choice: kill target, moment, round ends, the clients' judgements."""
    server_share: float = 0.5
    """Chance that a trial kills the server (else the worker)."""
    end_round_share: float = 0.3
    """Chance that a server-kill trial ends the round first (worker trials always do, so
    the worker is killed while it trains or prepares)."""
    load_s: tuple[float, float] = (0.2, 2.5)
    """Uniform range of the time between a trial's start (or round end) and its kill."""
    think_s: float = 0.02
    """Most time a client waits between two answered submissions (uniform)."""
    usable_timeout_s: float = 240.0
    """Longest wait for the session to be usable again before the trial counts as stuck."""
    training: str = "continuous"
    """The session's training mode: "continuous" (the app's default: the worker trains PPO
    and refits while the clients answer, and at a round's end cuts the next round from the
    latest rollouts and opens it before committing the round, so kills land mid-PPO,
    mid-refit, mid-cut and between opening a round and committing the one before) or
    "rounds" (PPO only after a round ends)."""
    db: str = "sqlite"
    """The server's database: "sqlite" (in the data directory), "postgresql" (a throw-away
    local cluster, fsync on) or the SQLAlchemy URL of an empty database."""


@dataclass
class Target:
    """Where the clients send (updated by the harness; read without a lock: str swaps)."""

    url: str
    session: str
    round: int = 0


@dataclass(frozen=True)
class Outcome:
    """What a run measured; `audit` is the database's side."""

    config: FaultConfig
    database: str  # how `config.db` was served ("a local PostgreSQL over its unix socket")
    kills: dict[str, int]
    recovery_s: dict[str, list[float]]  # kill → API answers, session resumed, by target
    open_s: dict[str, list[float]]  # kill → the round open again (after any training)
    stuck: int
    failures: list[str]  # session errors other than a killed worker
    audit: Audit
    answered_200: int  # retries answered with the stored judgement
    usable_at_end: bool
    wall_s: float


class ServeProcess:
    """`groupwise serve` on a free port of `data` (resuming its session after a restart)."""

    def __init__(self, data: Path, settings: dict[str, Any], db: str | None) -> None:
        self.data = data
        self.settings = settings
        self.db = db
        self.log = data.parent / "server.log"
        self.process: subprocess.Popen[str] | None = None

    def start(self) -> tuple[str, str]:
        command = [sys.executable, "-m", "groupwise.cli", "serve", "--env", "GridWorld"]
        command += ["--data", str(self.data), "--port", "0"]
        command += ["--settings", json.dumps(self.settings)]
        command += ["--db", self.db] if self.db else []
        env = {**os.environ, "PYTHONWARNINGS": "ignore", "PYTHONUNBUFFERED": "1"}
        with open(self.log, "ab") as log:
            self.process = subprocess.Popen(
                [*command, *FLAGS], stdout=subprocess.PIPE, stderr=log, text=True, env=env
            )
        assert self.process.stdout is not None
        for line in self.process.stdout:
            if found := URL.search(line):
                threading.Thread(target=self.process.stdout.read, daemon=True).start()
                return found.group(1), found.group(2)
        raise RuntimeError(f"the server did not start; see {self.log}")

    def kill(self) -> None:
        assert self.process is not None
        self.process.kill()
        self.process.wait(timeout=30)

    def stop(self) -> None:
        if self.process is None or self.process.poll() is not None:
            return
        self.process.terminate()
        try:
            self.process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(timeout=10)


def _judgement(rng: np.random.Generator, round_index: int) -> dict[str, Any]:
    sizes = rng.integers(1, 4, size=2)
    picked = rng.choice(POOL, size=int(sizes.sum()), replace=False)
    return {
        "client_id": rng.bytes(12).hex(),
        "round": round_index,
        "left": [f"b{i}" for i in picked[: sizes[0]]],
        "right": [f"b{i}" for i in picked[sizes[0] :]],
        "label": str(rng.choice(["left", "right", "equal"])),
        "source": "explored",
        "seconds": float(rng.uniform(0, 20)),
    }


def _client(
    target: Target, ledger: Ledger, rng: np.random.Generator, stop: threading.Event, think: float
) -> None:
    """Submit judgements until `stop`; resend one that got no answer with the same client_id."""
    pending: dict[str, Any] | None = None
    with httpx.Client(timeout=15) as http:
        while not stop.is_set():
            if pending is None:
                pending = _judgement(rng, target.round)
                ledger.sent(pending)
            try:
                response = http.post(
                    f"{target.url}/api/sessions/{target.session}/judgements", json=pending
                )
            except httpx.HTTPError:
                ledger.in_doubt(pending["client_id"])
                stop.wait(0.05)  # the server is gone or restarting: send it again
                continue
            ledger.answered(pending["client_id"], response.status_code, response.text)
            pending = None
            # a refusal is mostly 409 while the round is closed: wait for the next one
            stop.wait(rng.uniform(0, think) if response.is_success else 0.25)


class Harness:
    """One run (module docstring)."""

    def __init__(self, config: FaultConfig, data: Path, db: str | None, described: str) -> None:
        self.config = config
        self.db_url = db or default_url(data)
        self.described = described
        self.rng = np.random.default_rng(config.seed)
        settings = {**SETTINGS, "training": config.training}
        self.server = ServeProcess(data, settings, db)
        self.ledger = Ledger()
        self.http = httpx.Client(timeout=15)
        self.worker_pids: set[int] = set()
        self.failures: list[str] = []

    def run(self) -> Outcome:
        tick = time.monotonic()
        url, session = self.server.start()
        target = Target(url, session)
        stop = threading.Event()
        streams = self.rng.spawn(self.config.clients)
        threads = [
            threading.Thread(
                target=_client, args=(target, self.ledger, s, stop, self.config.think_s)
            )
            for s in streams
        ]
        kills = {"server": 0, "worker": 0}
        recovery: dict[str, list[float]] = {"server": [], "worker": []}
        reopened: dict[str, list[float]] = {"server": [], "worker": []}
        stuck = 0
        try:
            target.round = self._usable(target, time.monotonic())[2]
            for thread in threads:
                thread.start()
            for _ in range(self.config.trials):
                kind = "server" if self.rng.random() < self.config.server_share else "worker"
                # rounds mode: a worker only works after a round ends; continuous: always
                trains_now = kind == "worker" and self.config.training == "rounds"
                if trains_now or self.rng.random() < self.config.end_round_share:
                    self._control(target, "end-round")
                time.sleep(self.rng.uniform(*self.config.load_s))
                killed_at, killed = self._kill(kind, target)
                kills[kind] += 1
                if kind == "server":
                    target.url, again = self.server.start()
                    assert again == target.session, f"resumed {again}, not {target.session}"
                try:
                    resumed_s, open_s, target.round = self._usable(target, killed_at, killed)
                    recovery[kind].append(resumed_s)
                    reopened[kind].append(open_s)
                except TimeoutError as error:
                    stuck += 1
                    code = self.server.process.poll() if self.server.process else None
                    alive = "runs" if code is None else f"exited with {code}"  # -9: killed
                    self.failures.append(
                        f"{error}; the server process {alive}; its log ends:\n{self._log_tail()}"
                    )
            usable = self._judge_once(target)
        finally:
            stop.set()
            for thread in threads:
                thread.join(timeout=30)
            self.server.stop()
            self.http.close()
        result = audit(self.db_url, target.session, self.ledger)
        return Outcome(
            config=self.config,
            database=self.described,
            kills=kills,
            recovery_s=recovery,
            open_s=reopened,
            stuck=stuck,
            failures=self.failures,
            audit=result.with_orphans(_alive(self.worker_pids)),
            answered_200=self.ledger.retried_ok,
            usable_at_end=usable,
            wall_s=time.monotonic() - tick,
        )

    def _kill(self, kind: str, target: Target) -> tuple[float, tuple[int, ...]]:
        """SIGKILL the server or the worker; (when, the worker pid killed if any)."""
        if kind == "server":
            self.server.kill()
            return time.monotonic(), ()
        pid = self._health(target).get("worker_pid")
        deadline = time.monotonic() + 10
        while pid is None and time.monotonic() < deadline:  # a worker may be starting
            time.sleep(0.05)
            pid = self._health(target).get("worker_pid")
        if pid is None:
            return time.monotonic(), ()
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        return time.monotonic(), (pid,)

    def _health(self, target: Target) -> dict[str, Any]:
        try:
            answer: dict[str, Any] = self.http.get(f"{target.url}/api/health").json()
        except (httpx.HTTPError, ValueError):
            return {}
        if answer.get("worker_pid") is not None:
            self.worker_pids.add(int(answer["worker_pid"]))
        return answer

    def _state(self, target: Target) -> dict[str, Any] | None:
        try:
            response = self.http.get(f"{target.url}/api/sessions/{target.session}")
        except httpx.HTTPError:
            return None
        self.ledger.control(response.status_code, "GET state", response.text)
        return response.json() if response.is_success else None

    def _control(self, target: Target, verb: str) -> None:
        try:
            response = self.http.post(f"{target.url}/api/sessions/{target.session}/{verb}")
        except httpx.HTTPError:
            return
        self.ledger.control(response.status_code, f"POST {verb}", response.text)

    def _usable(
        self, target: Target, since: float, killed: tuple[int, ...] = ()
    ) -> tuple[float, float, int]:
        """(seconds from `since` until the session resumed, until its round was open, that
        round) once the round is open again; `killed`: the worker pid just killed. Raises
        TimeoutError after `usable_timeout_s`."""
        deadline = time.monotonic() + self.config.usable_timeout_s
        resumed: float | None = None
        last: dict[str, Any] | None = None
        while time.monotonic() < deadline:
            state = self._state(target)
            last = state if state is not None else last
            if state is not None and state["phase"] == "failed":
                error = str(state["error"])
                if not error.startswith(WORKER_DIED) and error not in self.failures:
                    self.failures.append(error)
                self._control(target, "retry")
                time.sleep(0.05)
                continue
            if state is not None and resumed is None:
                busy = state["phase"] in ("preparing", "training")
                # the killed worker may answer for a few ms more: only a new one counts
                if not busy or self._health(target).get("worker_pid") not in (None, *killed):
                    resumed = time.monotonic() - since
            if state is not None and state["phase"] == "ready" and resumed is not None:
                return resumed, time.monotonic() - since, int(state["round"])
            if state is not None and state["phase"] == "finished":
                raise TimeoutError("the session finished: raise FLAGS' --rounds")
            time.sleep(0.05)
        seen = "no answer" if last is None else _described(last)
        raise TimeoutError(
            f"the session was not usable within {self.config.usable_timeout_s} s (last seen: "
            f"{seen}; health {self._health(target)})"
        )

    def _log_tail(self, lines: int = 40) -> str:
        """The last `lines` lines of the server's log (its worker's included)."""
        try:
            text = self.server.log.read_text(errors="replace")
        except OSError as error:
            return f"(no log: {error})"
        return "\n".join(text.splitlines()[-lines:])

    def _judge_once(self, target: Target) -> bool:
        """Whether one more judgement is taken (201) after the last recovery."""
        body = _judgement(self.rng, target.round)
        self.ledger.sent(body)
        try:
            response = self.http.post(
                f"{target.url}/api/sessions/{target.session}/judgements", json=body
            )
        except httpx.HTTPError:
            return False
        self.ledger.answered(body["client_id"], response.status_code, response.text)
        return response.status_code == 201


def _described(state: dict[str, Any]) -> str:
    """The fields of a session's state that say where it stands."""
    keys = ("phase", "round", "error", "failed_phase", "progress")
    return ", ".join(f"{k} {state.get(k)!r}" for k in keys if k in state)


def _alive(pids: set[int]) -> int:
    """How many of the worker processes `pids` still exist (Linux: a reused pid running
    something else is not counted)."""
    alive = 0
    for pid in pids:
        try:
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            continue
        alive += b"multiprocessing" in cmdline or b"groupwise" in cmdline
    return alive


def run(config: FaultConfig) -> Outcome:
    """One harness run on a temporary data directory and `config.db`."""
    with tempfile.TemporaryDirectory() as tmp, database(config.db) as (url, described):
        data = Path(tmp) / "data"
        data.mkdir()
        try:
            return Harness(config, data, url, described).run()
        except BaseException:
            log = Path(tmp) / "server.log"
            if log.exists():
                sys.stderr.write(log.read_text(errors="replace")[-5000:])
            raise


def _median(values: Sequence[float]) -> str:
    return f"{statistics.median(values):.1f}" if values else "–"


def table(outcome: Outcome) -> str:
    a = outcome.audit
    back, reopened = outcome.recovery_s, outcome.open_s
    every = back["server"] + back["worker"]
    lines = [
        "| database | trials | server kills | worker kills | sent | acknowledged "
        "| retried → 200 | stored "
        "| lost | duplicated | half-stored | altered | 5xx | stuck | orphan workers "
        "| median recovery s (server / worker) | max recovery s "
        "| median round open again s (server / worker) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---|",
        f"| {a.database} | {outcome.config.trials} "
        f"| {outcome.kills['server']} | {outcome.kills['worker']} "
        f"| {a.sent} | {a.acknowledged} | {outcome.answered_200} | {a.stored} | {a.lost} "
        f"| {a.duplicated} | {a.half_stored} | {a.altered} | {a.server_errors} "
        f"| {outcome.stuck} | {a.orphans} | {_median(every)} "
        f"({_median(back['server'])} / {_median(back['worker'])}) "
        f"| {max(every, default=0):.1f} "
        f"| {_median(reopened['server'])} / {_median(reopened['worker'])} |",
    ]
    notes = [
        f"- database: {a.database}, {outcome.database}",
        "- recovery: from the kill until the API answers with the session not failed and, "
        "mid-step, a new worker started (after `POST /retry` for a killed worker); round open "
        "again: until the session is `ready`, which after an ended round includes its training "
        "and the next round's preparation",
        f"- stored without an answer (the kill came between commit and answer, or the last "
        f"resend was cut short): {a.stored_unanswered}; refused (4xx, e.g. 409 while the "
        f"round was closed): {a.refused}",
        f"- one more judgement after the last recovery: "
        f"{'201' if outcome.usable_at_end else 'FAILED'}",
        f"- wall time {outcome.wall_s / 60:.1f} min, {outcome.config.clients} clients, seed "
        f"{outcome.config.seed}, {os.cpu_count()} CPUs, load average "
        f"{os.getloadavg()[0]:.1f}",
    ]
    notes += [f"- session error other than a killed worker: {e}" for e in outcome.failures]
    notes += [f"- {problem}" for problem in a.problems[:20]]
    return "\n".join([*lines, "", *notes])


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--trials", type=int, default=100)
    parser.add_argument("--clients", type=int, default=4)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--fuzz-cases", type=int, default=10_000, help="0: no fuzz")
    parser.add_argument("--training", choices=("continuous", "rounds"), default="continuous")
    parser.add_argument(
        "--db",
        default="sqlite",
        help="sqlite (default), postgresql (a throw-away local cluster) or a database URL",
    )
    args = parser.parse_args([] if argv is None else list(argv))
    config = FaultConfig(
        trials=args.trials,
        clients=args.clients,
        seed=args.seed,
        training=args.training,
        db=args.db,
    )
    outcome = run(config)
    print(
        f"Fault injection: {args.trials} SIGKILLs of `groupwise serve` or its training worker "
        f"while {args.clients} clients submit judgements (GridWorld, 16 behaviours a round, "
        f"{args.training} training, {outcome.database}).\n",
        flush=True,
    )
    print(table(outcome), flush=True)
    if args.fuzz_cases > 0:
        from benchmarks import fuzz

        print("\n### schemathesis against the live API (on SQLite)\n", flush=True)
        fuzz.main(["--cases", str(args.fuzz_cases), "--seed", str(args.seed)])


if __name__ == "__main__":
    main(sys.argv[1:])
