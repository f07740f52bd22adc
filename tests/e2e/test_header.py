"""The status bar stays one line at 1366 × 768 whatever it says (issue 23): the longest env
name, "reconnecting…" while the event stream is down, "End round" and "Finish now" waiting
for their second click; a name longer than the bar can hold is cut with an ellipsis and
shown whole in its title. Once the session is finished, the round's timer, counters and
"End round" are gone. Screenshots: header-reconnecting.png, finished.png (1366 × 768)."""

import json
import re
from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

LONGEST_ENV = "MountainCarContinuous"
"""The widest env name the app offers (253 px with " · groupwise" at 14 px, against 235 px
for InvertedPendulum-v5 and 204 px for myenv:MyDot-v0); no MuJoCo, so its pool is quick."""
QUICK = {
    "pool_size": 8,
    "ppo_steps_per_round": 0,
    "eval_episodes": 0,
    "frame_size": 64,
    "render_workers": 1,
}
"""Small, quick rounds (as conftest's SETTINGS)."""
# Budgets that make the counters as wide as a session's usually are: "0 / 20", "0:00 / 10:00".
WIDE = {"round_seconds": 600, "comparisons_per_round": 20, "rounds": 100}

LINE = """(bar) => {
    const style = getComputedStyle(bar);
    const px = (name) => parseFloat(style[name]);
    const shown = [...bar.children].filter((el) => el.getClientRects().length > 0);
    const boxes = shown.map((el) => el.getBoundingClientRect());
    const line = Math.max(...boxes.map((b) => b.height)) + px('paddingTop') + px('paddingBottom')
        + px('borderTopWidth') + px('borderBottomWidth');
    return {
        height: bar.getBoundingClientRect().height,
        line: Math.max(line, px('minHeight') || 0),
        top: Math.max(...boxes.map((b) => b.top)),
        bottom: Math.min(...boxes.map((b) => b.bottom)),
        right: Math.max(...boxes.map((b) => b.right)),
        inner: bar.getBoundingClientRect().right - px('paddingRight'),
        page: document.documentElement.scrollWidth,
    };
}"""


def _one_line(page: Page) -> None:
    """Every control of the status bar in one row, none past its right edge."""
    m = page.locator(".statusbar").evaluate(LINE)
    assert m["height"] <= m["line"] + 0.5, m  # as high as its tallest control: one line
    assert m["top"] < m["bottom"], m  # every control overlaps every other vertically
    assert m["right"] <= m["inner"] + 0.5, m  # nothing pushed out on the right
    assert m["page"] <= 1366, m


def _ready_session(server: Server, env: str, **settings: Any) -> str:
    body = {"env": env, "mode": "groupwise", "settings": {**QUICK, **settings}}
    state = server.api("POST", "/api/sessions", body)
    server.wait_phase(state["id"], "ready", round_index=0)
    return str(state["id"])


def test_the_header_stays_one_line_in_its_widest_states(
    server: Server, page: Page, shot: Any
) -> None:
    sid = _ready_session(server, LONGEST_ENV, **WIDE)
    # The event stream is down from the start: the page keeps reconnecting.
    page.route(re.compile(r"/api/sessions/[^/]+/events"), lambda route: route.abort())
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(8)
    bar = page.locator(".statusbar")
    expect(bar.locator(".conn")).to_have_text("reconnecting…")
    meta = bar.locator(".meta")
    expect(meta).to_have_text(f"{LONGEST_ENV} · groupwise")
    expect(meta).to_have_attribute("title", re.compile(f"^{LONGEST_ENV} · groupwise · session "))
    expect(bar.locator(".timer")).to_have_text("0:00 / 10:00")
    _one_line(page)

    # Both two-click buttons waiting for their second click (4 s), still one line.
    end = page.get_by_role("button", name="End round")
    end_width = end.bounding_box()["width"]
    end.click()
    waiting = page.get_by_role("button", name="Click again to end the round")
    expect(waiting).to_have_text("Click again")
    page.get_by_role("button", name="Finish now").click()
    expect(page.get_by_role("button", name="Click again to finish the session")).to_be_visible()
    assert waiting.bounding_box()["width"] == pytest.approx(end_width, abs=0.5)
    _one_line(page)
    shot(page, "header-reconnecting")

    # Waited out, the buttons read as before; nothing was ended.
    expect(page.get_by_role("button", name="End round")).to_have_text("End round", timeout=6000)
    expect(page.get_by_role("button", name="Finish now")).to_have_text("Finish now")
    assert server.api("GET", f"/api/sessions/{sid}")["phase"] == "ready"


def test_a_name_too_long_for_the_bar_is_cut_and_shown_whole_in_its_title(
    server: Server, page: Page
) -> None:
    """Any `module:Env-v0` id may name a session's env: the bar cuts it, not the controls."""
    sid = _ready_session(server, "GridWorld", **WIDE)
    long_name = "my_company.research.locomotion_envs:MyExtremelyLongCustomEnvironment-v12"

    def renamed(route: Any) -> None:
        response = route.fetch()
        state = response.json()
        state["env"] = long_name
        route.fulfill(response=response, body=json.dumps(state))

    # every answer that is the session's state: reading it, and reporting the round shown
    page.route(re.compile(f"/api/sessions/{sid}(/rounds/\\d+/shown)?$"), renamed)
    # the stream's state events would bring the real name back
    page.route(re.compile(r"/api/sessions/[^/]+/events"), lambda route: route.abort())
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(8)
    meta = page.locator(".statusbar .meta")
    expect(meta).to_have_attribute("title", re.compile(f"^{re.escape(long_name)} · groupwise"))
    assert meta.evaluate("el => el.scrollWidth > el.clientWidth"), "the name is cut"
    assert meta.evaluate("el => getComputedStyle(el).textOverflow") == "ellipsis"
    page.get_by_role("button", name="End round").click()
    expect(page.get_by_role("button", name="Click again to end the round")).to_be_visible()
    _one_line(page)


def test_the_finished_page_shows_no_round_timer_counters_or_end_round(
    server: Server, page: Page, shot: Any
) -> None:
    sid = _ready_session(server, "GridWorld", rounds=1, round_seconds=600, final_steps=0)
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(8)
    bar = page.locator(".statusbar")
    expect(bar.get_by_role("timer")).to_be_visible()
    expect(bar.locator(".counts")).to_be_visible()
    page.get_by_role("button", name="End round").click()
    page.get_by_role("button", name="Click again to end the round").click()

    expect(page.get_by_role("region", name="Session results")).to_be_visible(timeout=180_000)
    expect(bar.locator(".phase")).to_have_text("finished")
    expect(bar.get_by_role("timer")).to_be_hidden()
    expect(bar.get_by_role("button", name="Pause the round timer")).to_be_hidden()
    expect(bar.locator(".counts")).to_be_hidden()
    expect(bar.get_by_text("Comparisons")).to_be_hidden()
    expect(bar.get_by_role("button", name="End round")).to_be_hidden()
    expect(bar.get_by_role("button", name="Finish now")).to_be_hidden()
    expect(page.locator(".keys-hint")).to_have_text("")  # no answer keys to hint at
    # what still applies: the session, its last round, the connection, the guide
    expect(bar.locator(".meta")).to_have_text("GridWorld · groupwise")
    expect(bar.locator(".round")).to_have_text(re.compile(r"^Round 0"))
    expect(bar.locator(".conn")).to_have_text("live")
    expect(bar.get_by_role("button", name="Show the guide")).to_be_visible()
    _one_line(page)
    shot(page, "finished")
