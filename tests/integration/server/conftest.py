"""A real `groupwise serve` process on a free loopback port, with a tiny GridWorld session.

`Server` starts ``python -m groupwise.cli serve`` on a temporary data directory, reads the
URL it prints, and waits for it to answer. Tests talk to it over HTTP (httpx) and may stop
it politely (SIGTERM), kill it (SIGKILL) and start it again on the same data.
"""

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

TINY_SETTINGS = {
    "recipe": "paper",  # no pre-training on a MuJoCo env: tests stay fast
    "frame_size": 32,
    "render_workers": 0,
    "eval_episodes": 1,
    "research": {
        "ppo": {"n_envs": 1, "n_steps": 64, "batch_size": 32, "n_epochs": 1, "net_arch": [16]},
        "reward": {"epochs": 1, "initial_epoch_multiplier": 2},
    },
}
"""Advanced settings that make a GridWorld round take seconds (see docs/app.md)."""
TINY_FLAGS = [
    "--pool-size", "16",
    "--fragment-length", "10",
    "--ppo-steps-per-round", "256",
    "--rounds", "2",
    "--round-seconds", "0",
    "--comparisons-per-round", "0",
]  # fmt: skip
URL = re.compile(r"open (http://\S+?)/\?session=(s-[0-9a-f]+)")


def wait_until(check: Callable[[], Any], timeout: float = 90.0, every: float = 0.2) -> Any:
    """Call `check` until it returns something truthy; fail after `timeout` seconds."""
    deadline = time.monotonic() + timeout
    while True:
        value = check()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"gave up waiting after {timeout} s (last: {value!r})")
        time.sleep(every)


class Server:
    """One `groupwise serve` process (see the module docstring)."""

    def __init__(self, data: Path, *args: str, settings: dict | None = None) -> None:
        self.data = data
        self.args = [
            "--data", str(data),
            "--port", "0",
            "--settings", json.dumps(settings or TINY_SETTINGS),
            *args,
        ]  # fmt: skip
        self.process: subprocess.Popen | None = None
        self.url = ""
        self.session = ""
        self.output = ""
        self.log = data.parent / f"{data.name}-server.log"

    def start(self) -> "Server":
        env = {**os.environ, "PYTHONWARNINGS": "ignore", "PYTHONUNBUFFERED": "1"}
        with open(self.log, "ab") as log:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "groupwise.cli", "serve", *self.args],
                stdout=subprocess.PIPE,
                stderr=log,
                text=True,
                env=env,
            )
        assert self.process.stdout is not None
        lines = []
        for line in self.process.stdout:
            lines.append(line)
            if found := URL.search(line):
                self.url, self.session = found.group(1), found.group(2)
                break
        self.output = "".join(lines)
        assert self.url, f"no URL printed: {self.output}\n{self.log.read_text()}"
        threading.Thread(target=self.process.stdout.read, daemon=True).start()
        wait_until(self._answers, timeout=60)
        return self

    def _answers(self) -> bool:
        try:
            return httpx.get(f"{self.url}/api/health", timeout=2).status_code == 200
        except httpx.HTTPError:
            return False

    def client(self, **kwargs: Any) -> httpx.Client:
        return httpx.Client(base_url=self.url, timeout=30, **kwargs)

    def state(self, session: str | None = None) -> dict:
        response = httpx.get(f"{self.url}/api/sessions/{session or self.session}", timeout=30)
        response.raise_for_status()
        return response.json()

    def wait_for(self, phase: str, round_index: int, session: str | None = None, timeout=120):
        def reached() -> dict | None:
            state = self.state(session)
            assert state["phase"] != "failed", state["error"]
            return state if (state["phase"], state["round"]) == (phase, round_index) else None

        return wait_until(reached, timeout=timeout)

    def stop(self) -> None:
        """SIGTERM, as Ctrl-C would; SIGKILL if it does not stop in time."""
        if self.process is None or self.process.poll() is not None:
            return
        self.process.send_signal(signal.SIGTERM)
        try:
            self.process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(timeout=10)

    def kill(self) -> None:
        """SIGKILL: the server gets no chance to clean up."""
        assert self.process is not None
        self.process.kill()
        self.process.wait(timeout=10)


@pytest.fixture
def serve(tmp_path) -> Iterator[Callable[..., Server]]:
    """Start servers on `tmp_path/data` (same data each call); all stopped at the end."""
    started: list[Server] = []

    def start(*args: str, settings: dict | None = None, data: Path | None = None) -> Server:
        server = Server(data or tmp_path / "data", *args, settings=settings).start()
        started.append(server)
        return server

    yield start
    for server in started:
        server.stop()


def judgement(round_index: int, left: list[str], right: list[str], **extra: Any) -> dict:
    import uuid

    return {
        "client_id": str(uuid.uuid4()),
        "round": round_index,
        "left": left,
        "right": right,
        "label": "left",
        "source": "explored",
        **extra,
    }
