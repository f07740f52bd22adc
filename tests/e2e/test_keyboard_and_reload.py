"""Keyboard focus and what a reload keeps (issue 23): the guide holds the focus while open
and gives it back; moving clips with Enter keeps the focus on the next clip's button; the
playback speed and the group clicks fill survive a reload."""

import re
from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

POOL = 16


def _open(page: Page, server: Server, sid: str) -> None:
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(POOL)
    expect(page.locator(".comparison .origin")).to_contain_text(
        re.compile("Suggested comparison|No suggestions left|Your selection"), timeout=15_000
    )


def _focused(page: Page) -> str:
    """The focused element's accessible name (its aria-label, else its text), or "<body>"."""
    return str(
        page.evaluate(
            """() => { const el = document.activeElement;
                if (!el || el === document.body) return '<body>';
                return el.getAttribute('aria-label') || el.textContent.trim(); }"""
        )
    )


def test_the_guide_holds_the_focus_and_gives_it_back(server: Server, page: Page) -> None:
    sid = server.new_session("groupwise")
    _open(page, server, sid)
    page.get_by_role("button", name="Next suggestion").focus()
    page.keyboard.press("?")
    guide = page.get_by_role("dialog", name="How this page works")
    expect(guide).to_be_visible()
    expect(page.get_by_role("button", name="Got it")).to_be_focused()
    inside = "() => document.querySelector('.guide').contains(document.activeElement)"
    for key in ["Tab"] * 5 + ["Shift+Tab"] * 3:
        page.keyboard.press(key)
        assert page.evaluate(inside), f"{key} left the guide for {_focused(page)}"
    # Tab, Tab, Enter (issue 23: it reached the New-session link) closes the guide only.
    page.keyboard.press("Tab")
    page.keyboard.press("Tab")
    page.keyboard.press("Enter")
    expect(guide).to_be_hidden()
    assert f"session={sid}" in page.url
    expect(page.locator(".arc.leaf")).to_have_count(POOL)
    expect(page.get_by_role("button", name="Next suggestion")).to_be_focused()
    # The page behind is usable again.
    page.keyboard.press("Tab")
    assert _focused(page) != "<body>"


def test_moving_clips_with_enter_keeps_the_focus(server: Server, page: Page, ui: Any) -> None:
    sid = server.new_session("groupwise")
    _open(page, server, sid)
    if page.locator(".clip").count():
        page.get_by_role("button", name="Clear groups").click()
    for leaf in ("b0", "b1", "b2"):
        ui.click_arc(leaf)
    ui.click_arc("b3", modifiers=("Alt",))
    expect(page.locator(".group-A .clip")).to_have_count(3)
    first, second, last = ui.clip_ids("A")

    # The last clip of A moves: the focus goes to the clip before it, then on along A.
    page.get_by_role("button", name=f"Move {last} to group B").focus()
    page.keyboard.press("Enter")
    expect(page.locator(f'.group-B .clip[data-id="{last}"]')).to_have_count(1)
    expect(page.get_by_role("button", name=f"Move {second} to group B")).to_be_focused()
    page.keyboard.press("Enter")
    expect(page.get_by_role("button", name=f"Move {first} to group B")).to_be_focused()
    # A's only clip moves: the focus follows it into B.
    page.keyboard.press("Enter")
    expect(page.locator(".group-A .clip")).to_have_count(0)
    expect(page.get_by_role("button", name=f"Move {first} to group A")).to_be_focused()

    # Removing B's clips one by one: the focus stays on a remove button, then goes to B's
    # fill button.
    for left in reversed(range(len(ui.clip_ids("B")))):
        page.get_by_role("button", name=f"Remove {ui.clip_ids('B')[-1]} from group B").focus()
        page.keyboard.press("Enter")
        expect(page.locator(".group-B .clip")).to_have_count(left)
        if left:
            before = ui.clip_ids("B")[-1]
            expect(page.get_by_role("button", name=f"Remove {before} from group B")).to_be_focused()
    expect(page.get_by_role("button", name="Let clicks fill group B")).to_be_focused()


def test_a_reload_keeps_the_speed_and_the_group_clicks_fill(
    server: Server, page: Page, ui: Any
) -> None:
    sid = server.new_session("groupwise")
    _open(page, server, sid)
    speed = page.get_by_role("combobox", name="Playback speed")
    expect(speed).to_have_value("1")
    speed.select_option("0.5")
    page.get_by_role("button", name="Let clicks fill group B").click()
    expect(page.get_by_role("button", name="Clicks fill group B").first).to_have_attribute(
        "aria-pressed", "true"
    )

    page.reload()
    _open(page, server, sid)
    expect(speed).to_have_value("0.5")
    expect(page.get_by_role("button", name="Clicks fill group B").first).to_have_attribute(
        "aria-pressed", "true"
    )
    expect(page.locator(".comparison .clip-timing")).to_contain_text("0.5")
    # A plain click now fills B.
    if page.locator(".clip").count():
        page.get_by_role("button", name="Clear groups").click()
    ui.click_arc("b5")
    expect(page.locator('.group-B .clip[data-id="b5"]')).to_have_count(1)
    rates = page.eval_on_selector_all(".comparison video", "vs => vs.map(v => v.playbackRate)")
    assert rates == [0.5]
