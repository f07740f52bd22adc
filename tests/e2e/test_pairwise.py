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
