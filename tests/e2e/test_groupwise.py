"""The groupwise interface end to end: arcs → groups → answer → database → history → reload
→ undo; one submission per answer; server errors shown; the round-end → progress → next
round cycle. Screenshots: groupwise.png, groupwise-hover.png, round-progress.png."""

import json
import re
from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page

Server = Any  # conftest.Server

POOL = 16


def _clusters(server: Server, sid: str, round_index: int = 0) -> list[tuple[str, list[str]]]:
    """Clusters (merge nodes) with 2…6 leaves, as (id, leaves), lowest level first."""
    tree = server.api("GET", f"/api/sessions/{sid}/rounds/{round_index}/tree")["tree"]
    found: list[tuple[int, str, list[str]]] = []

    def walk(node: dict[str, Any]) -> list[str]:
        if not node["children"]:
            return [node["id"]]
        leaves = [leaf for child in node["children"] for leaf in walk(child)]
        if node["id"] != "root" and 2 <= len(leaves) <= 6 and node["kind"] == "merge":
            found.append((node["level"], node["id"], leaves))
        return leaves

    walk(tree)
    return [(i, leaves) for _, i, leaves in sorted(found, key=lambda f: f[0])]


def _disjoint_pair(
    clusters: list[tuple[str, list[str]]],
) -> tuple[tuple[str, list[str]], tuple[str, list[str]]]:
    for i, (a, la) in enumerate(clusters):
        for b, lb in clusters[i + 1 :]:
            if not set(la) & set(lb):
                return (a, la), (b, lb)
    raise AssertionError(f"no two disjoint clusters of 2–6 behaviours in {clusters}")


def _open(page: Page, server: Server, sid: str) -> None:
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(POOL)


def _has_suggestion(server: Server, sid: str, round_index: int = 0) -> bool:
    reply = server.api("POST", f"/api/sessions/{sid}/rounds/{round_index}/next-suggestion", {})
    return reply["suggestion"] is not None


def _expect_prefilled_or_empty_state(
    page: Page, server: Server, sid: str, round_index: int = 0
) -> None:
    """Both groups empty: the next suggestion fills them (SPEC §5); with none, a message."""
    origin = page.locator(".comparison .origin")
    if _has_suggestion(server, sid, round_index):
        expect(page.locator(".group-A .clip").first).to_be_visible()
        expect(page.locator(".group-B .clip").first).to_be_visible()
        expect(origin).to_contain_text("Suggested comparison")
    else:
        expect(origin).to_contain_text("No suggestions left: choose groups in the chart.")
        expect(page.locator(".group-A .group-empty")).to_be_visible()


def _settled(page: Page) -> None:
    """The suggestion the page asks for when it opens (and after each answer) has come, or
    there was none: the groups are the suggestion's, the person's, or empty for good."""
    expect(page.locator(".comparison .origin")).to_contain_text(
        re.compile("Suggested comparison|No suggestions left|Your selection"), timeout=15_000
    )


def _fill_groups(page: Page, server: Server, sid: str, ui: Any) -> tuple[list[str], list[str]]:
    """Fills A and B by clicking two disjoint clusters (a click replaces the group; a
    suggested group, in A or in B, is not clicked again, which would toggle its behaviours
    out)."""
    _settled(page)
    shown = [set(ui.clip_ids("A")), set(ui.clip_ids("B"))]
    clusters = [c for c in _clusters(server, sid) if set(c[1]) not in shown]
    (node_a, leaves_a), (node_b, leaves_b) = _disjoint_pair(clusters)
    ui.click_arc(node_a)
    expect(page.locator(".group-A .clip")).to_have_count(len(leaves_a))
    ui.click_arc(node_b, modifiers=("Alt",))  # Alt-click: the other group
    expect(page.locator(".group-B .clip")).to_have_count(len(leaves_b))
    return leaves_a, leaves_b


def test_select_answer_reload_undo(server: Server, page: Page, ui: Any, shot: Any) -> None:
    sid = server.new_session("groupwise")
    _open(page, server, sid)

    _expect_prefilled_or_empty_state(page, server, sid)
    expect(page.locator(".comparison .clip-timing")).to_have_text("1 s · real speed")
    shot(page, "groupwise-start")
    if page.locator(".clip").count():
        page.get_by_role("button", name="Clear groups").click()
    expect(page.locator(".clip")).to_have_count(0)
    expect(page.get_by_role("button", name="Group A (left) is better")).to_be_disabled()

    # Two groups through arcs: a click fills A; G switches the target; a click fills B.
    (node_a, leaves_a), (node_b, leaves_b) = _disjoint_pair(_clusters(server, sid))
    ui.click_arc(node_a)
    expect(page.locator(".group-A .clip")).to_have_count(len(leaves_a))
    page.keyboard.press("g")
    expect(page.get_by_role("button", name="Clicks fill group B").first).to_have_attribute(
        "aria-pressed", "true"
    )
    ui.click_arc(node_b)
    expect(page.locator(".group-B .clip")).to_have_count(len(leaves_b))
    ui.expect_group("A", leaves_a)
    ui.expect_group("B", leaves_b)
    expect(page.locator(f'.arc[data-id="{leaves_a[0]}"]')).to_have_attribute(
        "aria-label", re.compile("in group A")
    )

    # Move a clip of A to B, remove one of B.
    moved = ui.clip_ids("A")[0]
    page.get_by_role("button", name=f"Move {moved} to group B").click()
    expect(page.locator(f'.group-B .clip[data-id="{moved}"]')).to_have_count(1)
    removed = leaves_b[0]
    page.get_by_role("button", name=f"Remove {removed} from group B").click()
    expect(page.locator(f'.clip[data-id="{removed}"]')).to_have_count(0)
    left, right = ui.clip_ids("A"), ui.clip_ids("B")
    assert moved in right and moved not in left and removed not in right + left
    assert len(left) == len(leaves_a) - 1 and len(right) == len(leaves_b)

    # Hovering a clip outlines its leaf in the chart.
    page.locator(f'.clip[data-id="{left[0]}"]').hover()
    expect(page.locator(".outline .hover-arc")).to_have_count(1)
    shot(page, "groupwise")
    page.mouse.move(3, 400)

    # Answer by key: ← left better.
    page.keyboard.press("ArrowLeft")
    expect(page.locator(".toast")).to_contain_text("Saved: left better")
    [j] = server.judgements(sid, 0)
    assert (j["left"], j["right"], j["label"], j["source"]) == (left, right, "left", "explored")
    assert j["edits"] >= 4
    assert len(j["pairs"]) == max(len(left), len(right))
    assert {p["a"] for p in j["pairs"]} == set(left) and {p["b"] for p in j["pairs"]} == set(right)
    assert all(p["label"] == 1.0 for p in j["pairs"])
    rows = server.db_rows(
        "SELECT id, label, undone, left, right FROM judgements WHERE session_id = ?", sid
    )
    assert [(r[1], r[2], json.loads(r[3]), json.loads(r[4])) for r in rows] == [
        ("left", 0, left, right)
    ]
    [(pairs,)] = server.db_rows("SELECT count(*) FROM pairs WHERE judgement_id = ?", rows[0][0])
    assert pairs == max(len(left), len(right))

    # The history edges appear and the answered leaves no longer count as uncompared.
    canvas = page.locator("canvas.chart-edges")
    expect(canvas).to_have_attribute("data-history", str(pairs))
    expect(page.locator(f'.arc[data-id="{left[0]}"]')).not_to_have_attribute(
        "aria-label", re.compile("not compared")
    )
    expect(page.locator(".statusbar .counts")).to_contain_text(f"Pairs{pairs}")

    # A reload restores the history from the server.
    page.reload()
    expect(page.locator(".arc.leaf")).to_have_count(POOL)
    expect(canvas).to_have_attribute("data-history", str(pairs))
    expect(page.locator(".statusbar .counts")).to_contain_text("Comparisons1")

    # Undo: the judgement is undone in the database, its edges go, its groups come back.
    page.keyboard.press("u")
    expect(page.locator(".toast")).to_contain_text("Last answer undone")
    expect(canvas).to_have_attribute("data-history", "0")
    assert server.judgements(sid, 0) == []
    assert server.db_rows("SELECT undone FROM judgements WHERE session_id = ?", sid) == [(1,)]
    assert server.db_rows("SELECT count(*) FROM pairs WHERE judgement_id = ?", rows[0][0]) == [(0,)]
    ui.expect_group("A", left, ordered=True)
    ui.expect_group("B", right, ordered=True)


def test_one_submission_per_answer_and_errors(
    server: Server, page: Page, ui: Any, shot: Any
) -> None:
    sid = server.new_session("groupwise")
    _open(page, server, sid)
    _fill_groups(page, server, sid, ui)

    held: list[Any] = []
    page.route(
        "**/judgements",
        lambda route: held.append(route) if route.request.method == "POST" else route.continue_(),
    )
    assert server.judgements(sid, 0) == [], "no answer before the keys below"
    page.keyboard.press("ArrowRight")
    page.keyboard.press("ArrowRight")
    page.get_by_role("button", name="Group B (right) is better").click(force=True)
    page.keyboard.press("d")
    page.wait_for_timeout(400)
    assert len(held) == 1, "one answer must be sent once"
    client_id = held[0].request.post_data_json["client_id"]
    held[0].continue_()
    expect(page.locator(".toast")).to_contain_text("Saved: right better")
    stored = server.judgements(sid, 0)
    assert [j["client_id"] for j in stored] == [client_id], stored

    # A refusal of the server is shown as its one sentence, and the answer can be given again.
    page.unroute("**/judgements")
    detail = "round 0 is closed; the open round is 1"
    page.route(
        "**/judgements",
        lambda route: (
            route.fulfill(status=409, json={"detail": detail})
            if route.request.method == "POST"
            else route.continue_()
        ),
    )
    _fill_groups(page, server, sid, ui)
    page.keyboard.press("w")
    alert = page.get_by_role("alert")
    expect(alert).to_contain_text(detail)
    expect(page.get_by_role("button", name="Both groups are about equal")).to_be_enabled()
    assert len(server.judgements(sid, 0)) == 1


def test_arcs_by_keyboard_and_previews(server: Server, page: Page, ui: Any, shot: Any) -> None:
    sid = server.new_session("groupwise")
    _open(page, server, sid)
    _settled(page)
    if page.locator(".clip").count():
        page.get_by_role("button", name="Clear groups").click()
    expect(page.locator(".clip")).to_have_count(0)

    # The chart is one tab stop; Shift + arrows move along a ring and outwards (plain arrows
    # are the answer keys); Enter selects.
    expect(page.locator(".keys-hint")).to_contain_text("Shift + arrows move through the chart")
    first = page.locator('.arc[tabindex="0"]')
    expect(first).to_have_count(1)
    first.focus()
    page.keyboard.press("Shift+ArrowRight")
    focused = page.evaluate("document.activeElement.dataset.id")
    expect(page.locator(".preview")).to_be_visible()
    expect(page.locator(".preview video")).to_have_count(1)
    # as long as the comparison says its clips are (GridWorld: 1 s), at real speed
    expect(page.locator(".preview .preview-timing")).to_have_text("1 s · real speed")
    page.keyboard.press("Enter")
    ui.expect_group("A", [focused])
    for _ in range(4):  # outwards to the first real cluster (padding arcs stand for one leaf)
        page.keyboard.press("Shift+ArrowUp")
        label = page.evaluate("document.activeElement.getAttribute('aria-label')")
        if label.startswith("cluster of"):
            break
    assert re.match(r"cluster of \d+ behaviours, level \d", label), label
    expect(page.locator(".preview .preview-title")).to_contain_text(
        re.compile(r"cluster of \d+ behaviours")
    )
    expect(page.locator(".preview video")).not_to_have_count(0)  # up to three medoids
    assert page.locator(".preview video").count() <= 3
    shot(page, "groupwise-hover")
    page.keyboard.press("Alt+Enter")  # the other group
    expect(page.locator(".group-B .clip").first).to_be_visible()
    assert focused not in ui.clip_ids("A")  # never in both groups
    page.keyboard.press("Shift+ArrowRight")  # the next cluster of the ring (disjoint) into A
    page.keyboard.press("Enter")
    expect(page.locator(".group-A .clip").first).to_be_visible()

    # With the focus still on an arc, ← answers (it used to move the chart's focus and
    # save nothing) and the toast confirms it.
    left, right = ui.clip_ids("A"), ui.clip_ids("B")
    page.keyboard.press("ArrowLeft")
    expect(page.locator(".toast")).to_contain_text("Saved: left better")
    [j] = server.judgements(sid, 0)
    assert (j["left"], j["right"], j["label"]) == (left, right, "left")
    shot(page, "groupwise-chart-focus-answer")
    # an answer key with nothing to answer says why
    page.wait_for_timeout(1000)  # the next suggestion may still be on its way
    page.get_by_role("button", name="Clear groups").click()
    expect(page.locator(".clip")).to_have_count(0)
    page.keyboard.press("ArrowRight")
    expect(page.locator(".toast")).to_contain_text("No answer saved: group A is empty")
    assert len(server.judgements(sid, 0)) == 1

    # Every control has an accessible name; no horizontal scrolling from 1366 × 768 up.
    unnamed = page.evaluate(
        """() => [...document.querySelectorAll('button, [role=button], select, input')]
            .filter((el) => el.offsetParent !== null || el.closest('svg'))
            .filter((el) => !(el.getAttribute('aria-label') || el.textContent.trim()
                              || el.closest('label') || el.labels?.length))
            .map((el) => el.outerHTML.slice(0, 80))"""
    )
    assert unnamed == []
    for width, height in [(1366, 768), (1920, 1080), (2560, 1440)]:
        page.set_viewport_size({"width": width, "height": height})
        page.wait_for_timeout(200)
        assert page.evaluate("document.documentElement.scrollWidth") <= width
        assert page.evaluate("document.documentElement.scrollHeight") <= height
    shot(page, "groupwise-2560")


def _export_rounds(server: Server, sid: str) -> tuple[list[int], list[int]]:
    """The round numbers of the session's JSONL export: its round lines, its judgements."""
    lines = [json.loads(line) for line in server.text(f"/api/sessions/{sid}/export").splitlines()]
    rounds = [line["round"] for line in lines if line["type"] == "round"]
    return rounds, [line["round"] for line in lines if line["type"] == "judgement"]


def test_round_end_progress_next_round(server: Server, page: Page, ui: Any, shot: Any) -> None:
    """Also: the page, the progress text and the export number the rounds alike (from 0)."""
    sid = server.new_session("groupwise")
    _open(page, server, sid)
    expect(page.locator(".statusbar .round")).to_have_text("Round 0 of 0–1")
    expect(page.locator(".exploration .panel-sub")).to_contain_text("round 0 ·")
    assert server.api("GET", f"/api/sessions/{sid}")["progress"]["message"] == "round 0 is open"

    # Pause and resume the round's timer.
    page.get_by_role("button", name="Pause the round timer").click()
    expect(page.get_by_role("timer")).to_have_class(re.compile("paused"))
    assert server.api("GET", f"/api/sessions/{sid}")["timer"]["paused"] is True
    page.get_by_role("button", name="Resume the round timer").click()
    expect(page.get_by_role("timer")).not_to_have_class(re.compile("paused"))

    _fill_groups(page, server, sid, ui)
    page.keyboard.press("a")
    expect(page.locator(".statusbar .counts")).to_contain_text("Comparisons1")
    assert _export_rounds(server, sid) == ([0], [0])
    end = page.locator(".end-round")
    end.click()
    expect(end).to_have_text("Click again")  # as wide as "End round": the bar keeps its line
    expect(end).to_have_accessible_name("Click again to end the round")
    end.click()

    overlay = page.locator(".workspace.groupwise .progress-overlay")
    expect(overlay).to_be_visible()
    expect(overlay.locator(".progress-title")).to_have_text(
        re.compile(r"Round 0 ended|Preparing round 1 of 0–1")
    )
    expect(overlay.get_by_role("progressbar")).to_have_attribute(
        "aria-valuenow", re.compile(r"^\d+$")
    )
    expect(page.get_by_role("button", name="Group A (left) is better")).to_be_disabled()
    shot(page, "round-progress")

    server.wait_phase(sid, "ready", round_index=1)  # fails fast, with the server log, on "failed"
    expect(page.locator(".statusbar .round")).to_have_text("Round 1 of 0–1", timeout=30_000)
    expect(page.locator(".statusbar .phase")).to_have_text("ready", timeout=180_000)
    expect(overlay).to_be_hidden()
    expect(page.locator(".exploration .panel-sub")).to_contain_text("round 1 ·")
    assert server.api("GET", f"/api/sessions/{sid}")["progress"]["message"] == "round 1 is open"
    assert _export_rounds(server, sid) == ([0, 1], [0])
    expect(page.locator(".arc.leaf")).to_have_count(POOL)
    _expect_prefilled_or_empty_state(page, server, sid, round_index=1)
