"""Benchmark: schemathesis against the live API, at least 10,000 generated requests.

The suite's fuzz test (`tests/unit/server/test_fuzz.py`) sends about 800 requests in-process;
this sends `--cases` (default 10,000) over HTTP to a running uvicorn: the app as
`groupwise serve` builds it (guards, SQLite in WAL mode, a real data directory), in a
process of its own, without the training worker (`--serve`, below) so that the sessions the
fuzzer creates wait instead of keeping the worker busy for hours; a groupwise and a
pairwise session are prepared first (their round 0 open) by the worker's own job, run in
that process.

Every operation of the OpenAPI schema but the event stream gets valid ("positive") and
invalid ("negative") requests, aimed three ways: at whatever session id the generator makes
up, and at each prepared session (so the handlers behind the 404 run too). Ending the round
comes last. Every answer must be below 500 and match the schema (status and body);
failures are counted, not stopped at. Prints the counts per check and the first failures.

    python -m benchmarks fuzz
    python -m benchmarks.fuzz [--cases 10000] [--seed 0]
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

URL = re.compile(r"open (http://\S+) (s-[0-9a-f]+) (s-[0-9a-f]+)")
TINY = {
    "pool_size": 16,
    "fragment_length": 10,
    "ppo_steps_per_round": 64,
    "comparisons_per_round": 0,
    "round_seconds": 0,
    "rounds": 2,
    "frame_size": 32,
    "render_workers": 0,
    "eval_episodes": 1,
}


def serve(data: Path) -> None:
    """The fuzzed server (module docstring): prints ``open URL GROUPWISE PAIRWISE``."""
    import socket

    import uvicorn

    from groupwise.server import AppConfig, create_app
    from groupwise.storage import sessions as repo
    from groupwise.storage.settings import SessionSettings
    from groupwise.worker.process import Worker

    app = create_app(AppConfig(data_dir=data, start_worker=False, static_dir=data / "no-web"))
    context = app.state.context
    ids = []
    for mode in ("groupwise", "pairwise"):
        with context.db.write() as s:
            settings = SessionSettings.model_validate(TINY)
            ids.append(repo.create_session(s, "GridWorld", mode, settings).id)
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    while worker.run_next():
        pass
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    print(f"open http://127.0.0.1:{sock.getsockname()[1]} {ids[0]} {ids[1]}", flush=True)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", access_log=False))
    server.run(sockets=[sock])


@dataclass
class Tally:
    """Cases sent and what the checks found, per operation."""

    cases: Counter[str] = field(default_factory=Counter)
    statuses: Counter[int] = field(default_factory=Counter)
    failures: Counter[str] = field(default_factory=Counter)
    examples: list[str] = field(default_factory=list)

    @property
    def total(self) -> int:
        return sum(self.cases.values())


def _fuzz(operation: Any, session_id: str | None, examples: int, seed: int, tally: Tally) -> int:
    """Send up to `examples` generated cases of `operation`; the number sent."""
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import seed as hypothesis_seed
    from hypothesis import strategies as st
    from schemathesis import GenerationMode
    from schemathesis.checks import not_a_server_error
    from schemathesis.specs.openapi.checks import response_schema_conformance

    checks = [not_a_server_error, response_schema_conformance]
    strategy = st.one_of(
        operation.as_strategy(GenerationMode.POSITIVE),
        operation.as_strategy(GenerationMode.NEGATIVE),
    )
    sent = 0

    @hypothesis_seed(seed)
    @given(case=strategy)
    @settings(
        max_examples=examples,
        deadline=None,
        database=None,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    def run(case: Any) -> None:
        nonlocal sent
        parameters = case.path_parameters
        if session_id is not None and parameters and "session_id" in parameters:
            parameters["session_id"] = session_id
            if "round_index" in parameters:
                parameters["round_index"] = 0
        response = case.call(timeout=30)
        sent += 1
        tally.statuses[response.status_code] += 1
        try:
            case.validate_response(response, checks=checks)
        except Exception as error:  # counted, not raised: the run goes on
            first = str(error).strip().splitlines()[0] if str(error).strip() else repr(error)
            tally.failures[f"{operation.label}: {first}"] += 1
            if len(tally.examples) < 10:
                tally.examples.append(
                    f"{operation.label} → {response.status_code}: {str(error)[:400]}"
                )

    run()
    tally.cases[operation.label] += sent
    return sent


def fuzz(url: str, sessions: Sequence[str], cases: int, seed: int) -> Tally:
    """At least `cases` generated requests to the API at `url` (module docstring)."""
    import schemathesis

    @schemathesis.serializer("application/x-ndjson", "application/vnd.apache.parquet")
    def _raw_body(ctx: Any, value: Any) -> bytes:
        """The import's bodies: generated strings or bytes, sent as they are."""
        if isinstance(value, bytes):
            return value
        return value.encode() if isinstance(value, str) else json.dumps(value).encode()

    schema = schemathesis.openapi.from_url(f"{url}/api/openapi.json")
    operations = [
        result.ok() for result in schema.exclude(path_regex=r"/events$").get_all_operations()
    ]
    # ending the round last keeps the open round's handlers reachable for the others
    operations.sort(key=lambda operation: operation.path.endswith("/end-round"))
    targets: list[str | None] = [None, *sessions]
    tally = Tally()
    rounds = 0
    while tally.total < cases:
        missing = cases - tally.total
        per = max(10, math.ceil(missing / (len(operations) * len(targets))))
        before = tally.total
        for index, operation in enumerate(operations):
            for variant, session_id in enumerate(targets):
                _fuzz(
                    operation, session_id, per, seed + 1000 * rounds + 10 * index + variant, tally
                )
        rounds += 1
        if tally.total == before:
            break  # nothing new can be generated
    return tally


def _count(item: tuple[str, int]) -> int:
    return item[1]


def report(tally: Tally, wall_s: float) -> str:
    server_errors = sum(n for status, n in tally.statuses.items() if status >= 500)
    lines = [
        "| operations | cases | 2xx | 4xx | 5xx | check failures | cases/s |",
        "|---:|---:|---:|---:|---:|---:|---:|",
        f"| {len(tally.cases)} | {tally.total} "
        f"| {sum(n for s, n in tally.statuses.items() if 200 <= s < 300)} "
        f"| {sum(n for s, n in tally.statuses.items() if 400 <= s < 500)} | {server_errors} "
        f"| {sum(tally.failures.values())} | {tally.total / wall_s:.0f} |",
        "",
        "- statuses: " + ", ".join(f"{s}: {n}" for s, n in sorted(tally.statuses.items())),
        "- fewest cases: "
        + ", ".join(
            f"{label} {n}" for label, n in sorted(tally.cases.items(), key=lambda x: x[1])[:3]
        ),
    ]
    lines += [f"- failure: {what} (×{n})" for what, n in tally.failures.most_common(10)]
    lines += [f"- example: {example}" for example in tally.examples[:3]]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--serve", type=Path, help=argparse.SUPPRESS)  # the fuzzed process
    args = parser.parse_args([] if argv is None else list(argv))
    if args.serve is not None:
        serve(args.serve)
        return
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "server.log"
        with open(log, "wb") as err:
            process = subprocess.Popen(
                [sys.executable, "-m", "benchmarks.fuzz", "--serve", str(Path(tmp) / "data")],
                stdout=subprocess.PIPE,
                stderr=err,
                text=True,
                env={**os.environ, "PYTHONWARNINGS": "ignore"},
            )
        try:
            assert process.stdout is not None
            found = None
            for line in process.stdout:
                if found := URL.search(line):
                    break
            if found is None:
                raise RuntimeError(f"the fuzzed server did not start:\n{log.read_text()[-3000:]}")
            threading.Thread(target=process.stdout.read, daemon=True).start()
            tick = time.monotonic()
            tally = fuzz(found.group(1), [found.group(2), found.group(3)], args.cases, args.seed)
            wall = time.monotonic() - tick
        finally:
            process.terminate()
            process.wait(timeout=30)
        crashed = log.read_text(errors="replace").count("Traceback")
    print(
        f"schemathesis {_version()} against the live API (uvicorn, SQLite), "
        f"{json.dumps(args.cases)} cases asked for, in {wall / 60:.1f} min; server log "
        f"tracebacks: {crashed}.\n"
    )
    print(report(tally, wall))


def _version() -> str:
    from importlib.metadata import version

    return version("schemathesis")


if __name__ == "__main__":
    main(sys.argv[1:])
