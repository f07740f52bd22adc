"""The pairwise baseline end to end: answer by key, the next pair at once, skip, equal,
undo; the judgements and pairs in the database. Screenshot: pairwise.png."""

from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page

Server = Any  # conftest.Server


def test_pairwise_round_trip(server: Server, page: Page, ui: Any, shot: Any) -> None:
    sid = server.new_session("pairwise")
    page.goto(f"{server.url}/?session={sid}")
    first = ui.pair()
    expect(page.locator(".pair-left figcaption")).to_have_text(f"Left · {first[0]}")
    expect(page.locator(".pair video")).to_have_count(2)
    # GridWorld's default behaviour: 30 steps at its 30 frames/s
    expect(page.locator(".pairwise .clip-timing")).to_have_text("1 s · real speed")
    shot(page, "pairwise")

    # ← left better: the following pair (prefetched) is on screen at once.
    shown = page.locator(".pair")
    expect(shown).to_have_attribute("data-pair", f"{first[0]}:{first[1]}")
    page.keyboard.press("ArrowLeft")
    expect(shown).not_to_have_attribute("data-pair", f"{first[0]}:{first[1]}", timeout=1000)
    second = ui.pair()
    assert second != first

    expect(page.locator(".toast")).to_contain_text("Saved: left better")
    [j] = server.judgements(sid, 0)
    assert (j["left"], j["right"], j["label"], j["source"]) == (
        [first[0]],
        [first[1]],
        "left",
        "pairwise",
    )
    assert j["pairs"] == [{"a": first[0], "b": first[1], "label": 1.0}]
    [(n,)] = server.db_rows("SELECT count(*) FROM pairs WHERE judgement_id = ?", j["id"])
    assert n == 1

    # ↓ skips: no judgement, and the server does not ask that pair again.
    page.keyboard.press("ArrowDown")
    expect(shown).not_to_have_attribute("data-pair", f"{second[0]}:{second[1]}", timeout=2000)
    third = ui.pair()
    page.wait_for_timeout(300)
    nxt = server.api("GET", f"/api/sessions/{sid}/pairwise/next")
    assert (nxt["pair"]["left"], nxt["pair"]["right"]) != second
    assert len(server.judgements(sid, 0)) == 1

    # W: equal; U: undo brings that pair back.
    page.keyboard.press("w")
    expect(page.locator(".toast")).to_contain_text("Saved: equal")
    judged = server.judgements(sid, 0)
    assert [x["label"] for x in judged] == ["left", "equal"]
    assert judged[1]["pairs"][0]["label"] == 0.5
    page.keyboard.press("u")
    expect(page.locator(".toast")).to_contain_text("Last answer undone")
    assert [x["label"] for x in server.judgements(sid, 0)] == ["left"]
    assert ui.pair() == third
    expect(page.locator(".statusbar .counts")).to_contain_text("Comparisons1")


WATCH_SWAPS = """() => {
    // every clip frame put into the pair: was its poster there, and its video hidden?
    window.__swaps = [];
    new MutationObserver((changes) => {
        for (const change of changes) for (const node of change.addedNodes) {
            if (!(node instanceof HTMLElement) || !node.matches('.clip-frame')) continue;
            const poster = node.querySelector('.clip-poster');
            window.__swaps.push({
                poster: poster.complete && poster.naturalWidth > 0,
                hidden: node.dataset.playing !== undefined
                    || getComputedStyle(node.querySelector('video')).opacity === '0',
            });
        }
    }).observe(document.querySelector('.pair'), {childList: true, subtree: true});
}"""


def test_a_new_clip_shows_its_poster_until_it_plays(server: Server, page: Page, ui: Any) -> None:
    """Issue 23: a new pair's clip could appear as an empty box before its first frame."""
    sid = server.new_session("pairwise", frame_size=96)
    page.goto(f"{server.url}/?session={sid}")
    first = ui.pair()
    frames = page.locator(".pair .clip-frame")
    expect(frames).to_have_count(2)
    expect(page.locator(".pair .clip-frame[data-playing]")).to_have_count(2)
    # the following pair's new clips (one or two: a behaviour may come again) wait in the
    # prefetch slot, their posters loaded
    page.wait_for_function(
        "() => { const p = [...document.querySelectorAll('.prefetch .clip-poster')];"
        " return p.length > 0 && p.every((i) => i.complete && i.naturalWidth > 0); }"
    )
    page.evaluate(WATCH_SWAPS)
    page.keyboard.press("ArrowLeft")
    expect(page.locator(".pair")).not_to_have_attribute("data-pair", f"{first[0]}:{first[1]}")
    expect(page.locator(".pair .clip-frame[data-playing]")).to_have_count(2)
    swaps = page.evaluate("() => window.__swaps")
    assert len(swaps) == 2 and all(s == {"poster": True, "hidden": True} for s in swaps), swaps
    # playing: the video shows, the poster only holds the frame's size
    shown = page.eval_on_selector_all(
        ".pair .clip-frame",
        "fs => fs.map((f) => [getComputedStyle(f.querySelector('video')).opacity,"
        " getComputedStyle(f.querySelector('.clip-poster')).visibility,"
        " f.querySelector('video').clientWidth])",
    )
    assert shown == [["1", "hidden", 96], ["1", "hidden", 96]], shown
