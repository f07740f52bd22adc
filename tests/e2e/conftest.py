"""Browser tests of the web UI against a real server (docs/app.md, SPEC §9).

One `groupwise serve` subprocess per test process (real SQLite, real training worker, a
temporary data directory), driven with Playwright for Python in Debian's Chromium; no
browser is downloaded. Each test makes its own small GridWorld session.

Needs: the web UI built into the package (`src/groupwise/static`, by `make` or
`cd web && npm ci && npm run build`), the Python package
`playwright` (its driver only; never `playwright install`), and Chromium at
`$GROUPWISE_CHROMIUM` (default /usr/bin/chromium). Missing any of them skips the tests,
unless `GROUPWISE_E2E_REQUIRED=1` (as `make test` sets): then it fails them.
Screenshots go to `$GROUPWISE_E2E_SCREENSHOTS` (default tests/e2e/screenshots/).
"""

import json
import os
import re
import socket
import sqlite3
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from groupwise.server.config import default_static_dir

REPO = Path(__file__).resolve().parents[2]
DIST = default_static_dir()  # what the server serves: src/groupwise/static in a checkout
CHROMIUM = Path(os.environ.get("GROUPWISE_CHROMIUM", "/usr/bin/chromium"))
SHOTS = Path(os.environ.get("GROUPWISE_E2E_SCREENSHOTS", Path(__file__).parent / "screenshots"))
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
# Small, quick rounds: 16 behaviours, tiny clips, no PPO or evaluation between rounds. The
# shared server's sessions train in rounds: in the app's default (continuous) every open
# session would keep the one worker busy by turns for the rest of the run; the continuous
# tests ask for it (test_training_curve.py).
SETTINGS: dict[str, Any] = {
    "recipe": "paper",  # no pre-training on a MuJoCo env: tests stay fast
    "training": "rounds",
    "pool_size": 16,
    "rounds": 2,
    "round_seconds": 0,
    "comparisons_per_round": 0,
    "ppo_steps_per_round": 0,
    "eval_episodes": 0,
    "frame_size": 64,
    "render_workers": 1,
}
READY_TIMEOUT_S = 180


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    here = Path(__file__).parent
    for item in items:
        if here in Path(str(item.fspath)).parents:
            item.add_marker(pytest.mark.e2e)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass
class Server:
    """A running `groupwise serve` and small helpers over its HTTP API."""

    url: str
    data: Path
    log: Path

    def api(self, method: str, path: str, body: Any = None) -> Any:
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(
            self.url + path, data=data, method=method, headers={"Content-Type": "application/json"}
        )
        with urllib.request.urlopen(request, timeout=30) as response:
            return json.loads(response.read() or b"null")

    def new_session(self, mode: str, **settings: Any) -> str:
        """A new GridWorld session whose first round is ready."""
        state = self.api(
            "POST",
            "/api/sessions",
            {"env": "GridWorld", "mode": mode, "settings": {**SETTINGS, **settings}},
        )
        self.wait_phase(state["id"], "ready", round_index=0)
        return str(state["id"])

    def wait_phase(self, sid: str, phase: str, round_index: int | None = None) -> dict[str, Any]:
        deadline = time.monotonic() + READY_TIMEOUT_S
        while True:
            state = self.api("GET", f"/api/sessions/{sid}")
            if state["phase"] == phase and round_index in (None, state["round"]):
                return dict(state)
            if state["phase"] == "failed":
                raise AssertionError(f"session {sid} failed: {state['error']}\n{self.tail()}")
            if time.monotonic() > deadline:
                raise AssertionError(f"session {sid} stuck in {state['phase']}\n{self.tail()}")
            time.sleep(0.3)

    def leaves(self, sid: str, round_index: int = 0) -> list[str]:
        """The behaviour ids of a round's tree, in the tree's order."""
        found: list[str] = []

        def walk(node: dict[str, Any]) -> None:
            if not node["children"]:
                found.append(node["id"])
            for child in node["children"]:
                walk(child)

        walk(self.api("GET", f"/api/sessions/{sid}/rounds/{round_index}/tree")["tree"])
        return found

    def text(self, path: str) -> str:
        """A GET answered with text (the JSONL export)."""
        with urllib.request.urlopen(self.url + path, timeout=30) as response:
            return str(response.read().decode())

    def judgements(
        self, sid: str, round_index: int, include_undone: bool = False
    ) -> list[dict[str, Any]]:
        flag = "&include_undone=true" if include_undone else ""
        return list(self.api("GET", f"/api/sessions/{sid}/judgements?round={round_index}{flag}"))

    def db_rows(self, sql: str, *params: Any) -> list[tuple[Any, ...]]:
        """Rows straight from the server's SQLite database (read-only)."""
        uri = f"file:{self.data / 'groupwise.db'}?mode=ro"
        with sqlite3.connect(uri, uri=True, timeout=10) as db:
            return db.execute(sql, params).fetchall()

    def tail(self, n: int = 40) -> str:
        lines = self.log.read_text(errors="replace").splitlines()
        return "\n".join(lines[-n:])


def _missing(reason: str) -> None:
    """Skip for a developer without the browser tools; fail where they are required (CI)."""
    if os.environ.get("GROUPWISE_E2E_REQUIRED") == "1":
        pytest.fail(reason)
    pytest.skip(reason)


def _playwright() -> Any:
    try:
        import playwright.sync_api
    except ImportError:
        _missing("the Python package playwright is not installed (pip install playwright)")
    return playwright.sync_api


def _serve(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """`groupwise serve` on a free port and a data directory of its own, until closed."""
    if not (DIST / "index.html").is_file():
        _missing(f"the web UI is not built ({DIST}): cd web && npm ci && npm run build")
    data = tmp_path_factory.mktemp("groupwise-data")
    log = data / "server.log"
    port = _free_port()
    exe = Path(sys.executable).with_name("groupwise")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "groupwise.cli"]
    cmd += ["serve", "--env", "GridWorld", "--data", str(data), "--port", str(port)]
    cmd += ["--settings", json.dumps(SETTINGS)]
    with log.open("w") as out:
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, cwd=REPO)
    srv = Server(url=f"http://127.0.0.1:{port}", data=data, log=log)
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                srv.api("GET", "/api/envs")
                break
            except (urllib.error.URLError, ConnectionError):
                if proc.poll() is not None or time.monotonic() > deadline:
                    raise AssertionError(f"groupwise serve did not start:\n{srv.tail()}") from None
                time.sleep(0.2)
        yield srv
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()


@pytest.fixture(scope="session")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """The server all tests share (each makes its own sessions)."""
    yield from _serve(tmp_path_factory)


@pytest.fixture(scope="module")
def own_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """A server for one test module alone: sessions it makes (e.g. of a MuJoCo env) keep
    the shared server's worker free, and stopping it stops their work."""
    yield from _serve(tmp_path_factory)


@pytest.fixture(scope="session")
def browser() -> Iterator[Any]:
    sync_api = _playwright()
    if not CHROMIUM.exists():
        _missing(f"no Chromium at {CHROMIUM} (set GROUPWISE_CHROMIUM)")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield b
        b.close()


GUIDE_SEEN = (
    "for (const mode of ['groupwise', 'pairwise'])"
    " localStorage.setItem('groupwise:guide-seen:' + mode, '1');"
)
"""Marks the app's guide as closed before (web/src/lib/guide.ts), so it does not open."""


def _page(browser: Any, guide_seen: bool) -> Iterator[Any]:
    context = browser.new_context(viewport={"width": 1366, "height": 768})
    if guide_seen:
        context.add_init_script(GUIDE_SEEN)
    pg = context.new_page()
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    yield pg
    context.close()
    assert not errors, f"uncaught errors in the page: {errors}"


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    """A 1366 × 768 page of a browser that has seen the app's guide before."""
    yield from _page(browser, guide_seen=True)


@pytest.fixture
def other_page(browser: Any) -> Iterator[Any]:
    """A second 1366 × 768 page, in a browser profile of its own: another person's (a shared
    session's annotator beside `page`)."""
    yield from _page(browser, guide_seen=True)


@pytest.fixture
def first_visit(browser: Any) -> Iterator[Any]:
    """A 1366 × 768 page of a fresh browser profile: the app's guide opens by itself."""
    yield from _page(browser, guide_seen=False)


@pytest.fixture
def shot() -> Any:
    """shot(page, name): saves a screenshot under SHOTS, returns its path."""
    SHOTS.mkdir(parents=True, exist_ok=True)

    def take(pg: Any, name: str) -> Path:
        path = SHOTS / f"{name}.png"
        pg.screenshot(path=str(path))
        return path

    return take


class UI:
    """Helpers over a page of the app (a fixture, so test modules import nothing)."""

    def __init__(self, page: Any) -> None:
        self.page = page

    def settled(self) -> None:
        """The suggestion the page asks for when it opens has come, or there was none."""
        _playwright().expect(self.page.locator(".comparison .origin")).to_contain_text(
            re.compile("Suggested comparison|No suggestions left|Your selection"), timeout=15_000
        )

    def open_round(self, server: Server, sid: str, leaves: int) -> None:
        """Opens a session's page, waits for its chart's `leaves` leaves and the opening
        suggestion, then clears the groups."""
        expect = _playwright().expect
        self.page.goto(f"{server.url}/?session={sid}")
        expect(self.page.locator(".chart-svg .arc.leaf")).to_have_count(leaves, timeout=30_000)
        self.settled()
        if self.page.locator(".clip").count():
            self.page.get_by_role("button", name="Clear groups").click()
        expect(self.page.locator(".clip")).to_have_count(0)

    def point_in(self, node_id: str) -> tuple[float, float]:
        """A point inside an arc's shape (an annulus' bounding-box centre may lie outside it)."""
        point = self.page.evaluate(
            """(id) => {
                const el = document.querySelector(`.arc[data-id="${id}"]`);
                const r = el.getBoundingClientRect();
                for (let fy = 0.5; fy < 1; fy += 0.05) for (const s of [1, -1])
                  for (let fx = 0.5; fx < 1; fx += 0.05) for (const t of [1, -1]) {
                    const x = r.left + r.width * (t > 0 ? fx : 1 - fx);
                    const y = r.top + r.height * (s > 0 ? fy : 1 - fy);
                    if (document.elementFromPoint(x, y) === el) return [x, y];
                  }
                return null;
            }""",
            node_id,
        )
        assert point is not None, f"arc {node_id} is not clickable"
        return point[0], point[1]

    def click_arc(self, node_id: str, modifiers: tuple[str, ...] = (), **kwargs: Any) -> None:
        """Clicks inside an arc's shape (`point_in`)."""
        point = self.point_in(node_id)
        for key in modifiers:
            self.page.keyboard.down(key)
        self.page.mouse.click(point[0], point[1], **kwargs)
        for key in reversed(modifiers):
            self.page.keyboard.up(key)

    def expect_group(self, group: str, ids: list[str], ordered: bool = False) -> None:
        """Waits until a group's clips are `ids` (the page renders on the next animation frame,
        so a count that the old groups already had proves nothing)."""
        want = list(ids) if ordered else sorted(ids)
        try:
            self.page.wait_for_function(
                """([sel, want, ordered]) => {
                    const ids = [...document.querySelectorAll(sel)].map((e) => e.dataset.id);
                    if (!ordered) ids.sort();
                    return JSON.stringify(ids) === JSON.stringify(want);
                }""",
                arg=[f".group-{group} .clip", want, ordered],
                timeout=5_000,
            )
        except Exception as err:
            got = self.clip_ids(group)
            raise AssertionError(f"group {group} is {got}, expected {ids}") from err

    def clip_ids(self, group: str) -> list[str]:
        """Behaviour ids of a group's clips, in order."""
        return list(
            self.page.eval_on_selector_all(
                f".group-{group} .clip", "els => els.map(e => e.dataset.id)"
            )
        )

    def pair(self) -> tuple[str, str]:
        """(left, right) behaviour ids of the pair on screen (pairwise mode), once one is."""
        shown = self.page.locator(".pair")
        sync_api = _playwright()
        sync_api.expect(shown).to_have_attribute("data-pair", re.compile(r"^b\d+:b\d+$"))
        left, right = str(shown.get_attribute("data-pair")).split(":")
        return left, right


@pytest.fixture
def ui(page: Any) -> UI:
    return UI(page)
