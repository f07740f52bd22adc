"""Where a stored comparison comes from (docs/app.md, "Where a comparison comes from"; issue
23): groups built in the chart over the suggestion loaded after an answer are `explored`; a
suggestion with one clip removed stays `suggested` with 1 edit. Right-click fills the other
group from the first try after a load."""

import json
import re
from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

POOL = 16


def _clusters(server: Server, sid: str) -> dict[str, list[str]]:
    """Clusters (merge nodes) of round 0 with 2…6 behaviours: id → leaves."""
    tree = server.api("GET", f"/api/sessions/{sid}/rounds/0/tree")["tree"]
    found: dict[str, list[str]] = {}

    def walk(node: dict[str, Any]) -> list[str]:
        if not node["children"]:
            return [node["id"]]
        leaves = [leaf for child in node["children"] for leaf in walk(child)]
        if node["kind"] == "merge" and node["id"] != "root" and 2 <= len(leaves) <= 6:
            found[node["id"]] = leaves
        return leaves

    walk(tree)
    return found


def _open(page: Page, server: Server, sid: str) -> None:
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(POOL)


def _suggestion_shown(page: Page) -> None:
    expect(page.locator(".comparison .origin")).to_have_text(
        "Suggested comparison · 0 edits", timeout=15_000
    )


def _judgements(server: Server, sid: str) -> list[dict[str, Any]]:
    """The session's judgements as its JSONL export has them."""
    lines = [json.loads(x) for x in server.text(f"/api/sessions/{sid}/export").splitlines()]
    return [x for x in lines if x["type"] == "judgement"]


def test_groups_built_in_the_chart_after_an_answer_are_explored(
    server: Server, page: Page, ui: Any, shot: Any
) -> None:
    sid = server.new_session("groupwise")
    _open(page, server, sid)
    _suggestion_shown(page)
    page.keyboard.press("ArrowUp")  # answer the first suggestion: the next one is loaded
    expect(page.locator(".toast")).to_contain_text("Saved: equal")
    _suggestion_shown(page)
    loaded = (ui.clip_ids("A"), ui.clip_ids("B"))

    # A by a click on a cluster, B by a right-click on another, one more for B by Alt-click.
    clusters = _clusters(server, sid)
    first, second = next(
        (a, b)
        for a in clusters
        for b in clusters
        if not set(clusters[a]) & set(clusters[b])
        and not set(clusters[a]) <= set(loaded[0])
        and not set(clusters[b]) <= set(loaded[1])
    )
    ui.click_arc(first)
    expect(page.locator(".group-A .clip")).to_have_count(len(clusters[first]))
    expect(page.locator(".comparison .origin")).to_have_text("Your selection · 1 edit")
    ui.click_arc(second, button="right")
    expect(page.locator(".group-B .clip")).to_have_count(len(clusters[second]))
    extra = next(f"b{i}" for i in range(POOL) if f"b{i}" not in clusters[first] + clusters[second])
    ui.click_arc(extra, modifiers=("Alt",))
    expect(page.locator(f'.group-B .clip[data-id="{extra}"]')).to_have_count(1)
    ui.expect_group("A", clusters[first])

    # Then edits: move one clip, remove one.
    moved = ui.clip_ids("A")[0]
    page.get_by_role("button", name=f"Move {moved} to group B").click()
    removed = clusters[second][0]
    page.get_by_role("button", name=f"Remove {removed} from group B").click()
    expect(page.locator(".comparison .origin")).to_have_text("Your selection · 5 edits")
    left, right = ui.clip_ids("A"), ui.clip_ids("B")
    shot(page, "groupwise-explored")
    page.keyboard.press("ArrowLeft")
    expect(page.locator(".toast")).to_contain_text("Saved: left better")

    suggested, own = _judgements(server, sid)
    assert (suggested["source"], suggested["edits"]) == ("suggested", 0)
    assert (own["left"], own["right"], own["label"]) == (left, right, "left")
    assert (own["source"], own["edits"]) == ("explored", 5)


def test_a_suggestion_with_a_clip_removed_stays_suggested(
    server: Server, page: Page, ui: Any
) -> None:
    sid = server.new_session("groupwise")
    _open(page, server, sid)
    _suggestion_shown(page)
    for _ in range(10):  # a suggestion with a group of two or more, to remove one from
        group = next((g for g in "AB" if len(ui.clip_ids(g)) >= 2), None)
        if group:
            break
        page.keyboard.press("n")
        _suggestion_shown(page)
    assert group, "no suggestion with a group of two behaviours"
    left, right = ui.clip_ids("A"), ui.clip_ids("B")
    removed = ui.clip_ids(group)[-1]
    page.get_by_role("button", name=f"Remove {removed} from group {group}").click()
    expect(page.locator(".comparison .origin")).to_have_text("Suggested comparison · 1 edit")
    page.keyboard.press("ArrowRight")
    expect(page.locator(".toast")).to_contain_text("Saved: right better")

    [j] = _judgements(server, sid)
    assert (j["source"], j["edits"], j["label"]) == ("suggested", 1, "right")
    assert (j["left"], j["right"]) == (
        [x for x in left if x != removed],
        [x for x in right if x != removed],
    )


def test_right_click_fills_b_on_the_first_try_after_a_load(
    server: Server, page: Page, ui: Any
) -> None:
    sid = server.new_session("groupwise")
    clusters = sorted(_clusters(server, sid).items(), key=lambda c: -len(c[1]))
    for load, (node, leaves) in enumerate(clusters[:3]):
        if load:
            page.reload()
        else:
            _open(page, server, sid)
        expect(page.locator(".arc.leaf")).to_have_count(POOL)
        expect(page.locator(".comparison .origin")).to_contain_text(
            re.compile("Suggested comparison|Your selection"), timeout=15_000
        )
        if set(leaves) <= set(ui.clip_ids("B")):
            page.get_by_role("button", name="Clear groups").click()
        ui.click_arc(node, button="right")
        ui.expect_group("B", leaves)
        expect(page.locator(f'.arc[data-id="{leaves[0]}"]')).to_have_attribute(
            "aria-label", re.compile("in group B")
        )
        # Clicks still fill A: the right-click did not switch the target.
        expect(page.get_by_role("button", name="Clicks fill group A").first).to_have_attribute(
            "aria-pressed", "true"
        )
