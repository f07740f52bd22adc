"""The app as a person first meets it: the guide on first open (closed for good, "?" brings
it back), the round's timer starting only when the round is on screen, tooltips and toasts
that never cover a control, and pairwise clips at their own size.
Screenshots: guide.png, groupwise-question.png, pairwise-clips.png."""

import re
import time
from datetime import UTC, datetime
from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page

Server = Any  # conftest.Server

GROUP_QUESTION = "Which group is closer to the behaviour you want?"
CLIP_QUESTION = "Which clip is closer to the behaviour you want?"

CONTROLS_UNDER = """(selector) => {
    // Rectangles of the visible controls that the element `selector` overlaps, outside it.
    const box = document.querySelector(selector).getBoundingClientRect();
    const hits = [];
    for (const el of document.querySelectorAll(
        'button, input, select, a[href], [role=button], .arc')) {
      if (el.closest(selector) || el.closest('.chart-wrap') && selector === '.preview') continue;
      const r = el.getBoundingClientRect();
      if (!r.width || !r.height || getComputedStyle(el).visibility === 'hidden') continue;
      if (r.left < box.right && box.left < r.right && r.top < box.bottom && box.top < r.bottom)
        hits.push((el.getAttribute('aria-label') || el.textContent || el.tagName).trim());
    }
    return hits;
}"""


def _when(value: str) -> datetime:
    """A time of the API ("…Z") or of the SQLite file (naive UTC), as naive UTC."""
    when = datetime.fromisoformat(value.replace("Z", "+00:00"))
    return when.astimezone(UTC).replace(tzinfo=None) if when.tzinfo else when


def _seconds(shown: str) -> int:
    """The elapsed part of the timer's text ("1:05 / 10:00"), in seconds."""
    minutes, seconds = shown.split(" / ")[0].split(":")
    return int(minutes) * 60 + int(seconds)


def test_the_guide_and_the_timer_on_first_open(
    server: Server, first_visit: Page, shot: Any
) -> None:
    page = first_visit
    sid = server.new_session("groupwise", round_seconds=600)
    time.sleep(4)  # the round waits, ready, before anybody opens the page
    waiting = server.api("GET", f"/api/sessions/{sid}")["timer"]
    assert (waiting["elapsed_s"], waiting["running"], waiting["shown_at"]) == (0, False, None)

    page.goto(f"{server.url}/?session={sid}")
    guide = page.get_by_role("dialog", name="How this page works")
    expect(guide).to_be_visible()
    expect(guide).to_contain_text("right-click")
    expect(guide).to_contain_text(GROUP_QUESTION)
    expect(page.locator(".arc.leaf")).to_have_count(16)
    shot(page, "guide")
    # The guide covers the round: no answer key acts, and the round's time does not run yet.
    page.keyboard.press("ArrowLeft")
    page.wait_for_timeout(1000)
    assert server.judgements(sid, 0) == []
    assert server.api("GET", f"/api/sessions/{sid}")["timer"]["shown_at"] is None

    page.get_by_role("button", name="Got it").click()
    expect(guide).to_be_hidden()
    # The round is on screen now: its timer starts from here, not from when it was ready.
    # Checked without a clock: the timer's run started at the round's first showing, at
    # least the 4 s waited above after the round opened (how the time counts from there: the
    # timer's unit tests in tests/unit/storage/), and the page's timer is not ahead of the
    # server's, read after it.
    timer = page.get_by_role("timer")
    expect(timer).to_have_text(re.compile(r"^\d+:\d\d / 10:00$"))
    deadline = time.monotonic() + 10
    while server.api("GET", f"/api/sessions/{sid}")["timer"]["shown_at"] is None:
        assert time.monotonic() < deadline, "the page never reported the round shown"
        time.sleep(0.2)
    on_page = _seconds(timer.inner_text())
    state = server.api("GET", f"/api/sessions/{sid}")
    assert state["timer"]["running"] and on_page <= state["timer"]["elapsed_s"] + 1
    [(opened_at, shown_at, started_at)] = server.db_rows(
        "SELECT r.opened_at, r.shown_at, s.timer_started_at FROM rounds r"
        ' JOIN sessions s ON s.id = r.session_id WHERE s.id = ? AND r."index" = 0',
        sid,
    )
    assert _when(started_at) == _when(shown_at)
    assert (_when(shown_at) - _when(opened_at)).total_seconds() >= 4
    assert _when(state["timer"]["shown_at"]) == _when(shown_at)

    # The question in the groupwise mode, in the pairwise mode's words.
    expect(page.get_by_role("heading", name=GROUP_QUESTION)).to_be_visible()
    expect(page.locator(".comparison .origin")).to_contain_text(
        re.compile("Suggested comparison|No suggestions left|Your selection"), timeout=15_000
    )
    shot(page, "groupwise-question")

    # "?" brings the guide back; Escape closes it; a reload remembers that it was closed.
    page.get_by_role("button", name="Show the guide").click()
    expect(guide).to_be_visible()
    page.keyboard.press("Escape")
    expect(guide).to_be_hidden()
    page.keyboard.press("?")
    expect(guide).to_be_visible()
    guide.get_by_role("button", name="Close the guide").click()
    page.reload()
    expect(page.locator(".arc.leaf")).to_have_count(16)
    page.wait_for_timeout(500)
    expect(guide).to_be_hidden()
    # a reload is not a first showing: the timer keeps the first one
    later = server.api("GET", f"/api/sessions/{sid}")["timer"]
    assert later["shown_at"] == state["timer"]["shown_at"]


def test_tooltips_and_toasts_never_cover_controls(server: Server, page: Page) -> None:
    sid = server.new_session("groupwise")
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(16)
    expect(page.locator(".comparison .origin")).to_contain_text(
        re.compile("Suggested comparison|No suggestions left|Your selection"), timeout=15_000
    )
    chart = page.locator(".exploration .chart-wrap").bounding_box()
    # Hover the leaves nearest the comparison panel and the legend: the preview stays in the
    # chart's area (it used to cover "A is better").
    for side in ("right", "bottom"):
        x, y = page.evaluate(
            """(side) => {
                let best = null;
                for (const el of document.querySelectorAll('.arc.leaf')) {
                  const r = el.getBoundingClientRect();
                  if (!best || r[side] > best[0]) best = [r[side], r.left + r.width / 2,
                                                          r.top + r.height / 2];
                }
                return best.slice(1);
            }""",
            side,
        )
        page.mouse.move(x, y)
        expect(page.locator(".preview")).to_be_visible()
        expect(page.locator(".preview video")).to_have_count(1)
        box = page.locator(".preview").bounding_box()
        assert chart["x"] <= box["x"] and box["x"] + box["width"] <= chart["x"] + chart["width"]
        assert chart["y"] <= box["y"] and box["y"] + box["height"] <= chart["y"] + chart["height"]
        assert page.evaluate(CONTROLS_UNDER, ".preview") == []
    page.mouse.move(3, 400)

    # A long toast (an answer key with nothing to answer) lies in the message bar, over no
    # control: not the legend's sliders, not the action buttons.
    if page.locator(".clip").count():
        page.get_by_role("button", name="Clear groups").click()
    expect(page.locator(".clip")).to_have_count(0)
    page.keyboard.press("ArrowRight")
    toast = page.locator(".toast")
    expect(toast).to_contain_text("No answer saved: group A is empty")
    assert page.evaluate(CONTROLS_UNDER, ".toast") == []
    assert page.locator(".messagebar").bounding_box()["y"] >= (
        page.locator(".workspace.groupwise").bounding_box()["y"]
        + page.locator(".workspace.groupwise").bounding_box()["height"]
        - 1
    )


def test_pairwise_clips_at_their_own_size(server: Server, page: Page, shot: Any) -> None:
    sid = server.new_session("pairwise", frame_size=240)
    page.goto(f"{server.url}/?session={sid}")
    expect(page.get_by_role("heading", name=CLIP_QUESTION)).to_be_visible()
    expect(page.locator(".pair video")).to_have_count(2)
    page.wait_for_function(
        "() => [...document.querySelectorAll('.pair video')].every((v) => v.videoWidth > 0)"
    )
    sizes = page.eval_on_selector_all(
        ".pair video", "vs => vs.map((v) => [v.videoWidth, v.clientWidth, v.clientHeight])"
    )
    # never scaled up (it used to fill ~660 px); the 1366 × 768 page has room for 240 px
    assert sizes == [[240, 240, 240], [240, 240, 240]], sizes
    shot(page, "pairwise-clips")


SHOWN_SIZE = """vs => vs.map((v) => {
    // the size the picture is drawn at inside the element, by its object-fit
    const fit = Math.min(v.clientWidth / v.videoWidth, v.clientHeight / v.videoHeight);
    const scale = {contain: fit, "scale-down": Math.min(1, fit), none: 1}[
        getComputedStyle(v).objectFit];
    return [v.videoWidth, Math.round(v.videoWidth * scale), v.clientWidth];
})"""


def test_group_clips_never_scaled_up(server: Server, page: Page) -> None:
    sid = server.new_session("groupwise", frame_size=96)
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".comparison .origin")).to_contain_text(
        re.compile("Suggested comparison"), timeout=15_000
    )
    page.wait_for_function(
        "() => [...document.querySelectorAll('.clip video')].every((v) => v.videoWidth > 0)"
    )
    sizes = page.eval_on_selector_all(".clip video", SHOWN_SIZE)
    assert sizes and all(native == 96 for native, _, _ in sizes), sizes
    # the cells of a small group are larger than the clips; the clips keep their own size
    assert max(cell for _, _, cell in sizes) > 96, sizes
    assert all(shown <= native for native, shown, _ in sizes), sizes
