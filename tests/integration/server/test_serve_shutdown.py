"""A stopped `groupwise serve` leaves no multiprocessing semaphore behind (issue 40: every
stop printed "17 leaked semaphore objects"): the on-demand clip renderers are shut down
with the app, and the training worker ends its own render and evaluation processes rather
than wait for them, so it exits cleanly before the supervisor would kill it."""

import json
import os
import signal
import subprocess
import sys
import threading

import httpx
import pytest
from tests.integration.server.conftest import TINY_FLAGS, TINY_SETTINGS, URL, wait_until


def leaf_clips(node: dict) -> list[str]:
    if node["kind"] == "leaf":
        return [node["clip"]]
    return [clip for child in node["children"] for clip in leaf_clips(child)]


def ready(client: httpx.Client, session: str) -> bool:
    try:
        return client.get(f"/api/sessions/{session}").json()["phase"] == "ready"
    except httpx.HTTPError:  # not listening yet
        return False


@pytest.mark.parametrize(
    "stop",
    [
        signal.SIGINT,
        # the same shutdown path as SIGINT (12 s on 2 cores): make test-slow runs it
        pytest.param(signal.SIGTERM, marks=pytest.mark.slow),
    ],
    ids=["SIGINT", "SIGTERM"],
)
def test_a_stopped_server_leaks_no_semaphore(tmp_path, stop):
    # the resource tracker warns through `warnings`: PYTHONWARNINGS=ignore would hide it
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    args = ["--data", str(tmp_path / "data"), "--port", "0", "--env", "GridWorld"]
    process = subprocess.Popen(
        [sys.executable, "-m", "groupwise.cli", "serve", *args, *TINY_FLAGS,
         "--settings", json.dumps(TINY_SETTINGS)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**env, "PYTHONUNBUFFERED": "1"},
    )  # fmt: skip
    assert process.stdout is not None and process.stderr is not None
    stderr: list[str] = []
    # read to EOF: every process holding the pipe has ended, the resource tracker included
    reader = threading.Thread(target=lambda: stderr.extend(process.stderr), daemon=True)
    reader.start()
    try:
        found = next(m for line in process.stdout if (m := URL.search(line)))
        threading.Thread(target=process.stdout.read, daemon=True).start()
        url, session = found.group(1), found.group(2)
        with httpx.Client(base_url=url, timeout=30) as client:
            wait_until(lambda: ready(client, session))
            tree = client.get(f"/api/sessions/{session}/rounds/0/tree").json()
            clip = leaf_clips(tree["tree"])[0]
            # rendered on demand by the server's render processes
            rendered = client.get(f"/clips/{clip}", timeout=120)
            assert rendered.status_code == 200 and rendered.content
        process.send_signal(stop)
        process.wait(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(timeout=10)
    reader.join(timeout=60)
    assert not reader.is_alive(), "a process of the server still holds its stderr"
    text = "".join(stderr)
    assert "leaked semaphore" not in text, text[-2000:]
    assert "Traceback" not in text, text[-2000:]
