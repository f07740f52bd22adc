"""A round of 1,000 behaviours on a real server (issue 22, items 3 and 6): the worker prepares
it with a poster per behaviour and the clips on demand; on the page a person selects a
cluster, hovers a leaf (its clip, rendered by the server when asked for, plays), answers,
and the judgement is stored. Clips load lazily: a video only for the clips in view.

GridWorld with 32 × 32 frames keeps the round cheap; the server renders each clip it is
asked for from the clip's recipe (`clips.on_demand`).
"""

from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect

N = 1000
READY = "(v) => v.readyState >= 2 && v.currentSrc.includes('/clips/')"
"""A video that has a clip URL and the data for its current frame (HAVE_CURRENT_DATA)."""


def _cluster(server: Any, sid: str, taken: set[str]) -> tuple[str, list[str]]:
    """A cluster of 2–8 behaviours (a group candidate) none of which is in `taken`."""
    tree = server.api("GET", f"/api/sessions/{sid}/rounds/0/tree")["tree"]
    found: list[tuple[str, list[str]]] = []

    def walk(node: dict[str, Any]) -> list[str]:
        if not node["children"]:
            return [node["id"]]
        leaves = [leaf for child in node["children"] for leaf in walk(child)]
        if node["kind"] == "merge" and 2 <= len(leaves) <= 8 and not set(leaves) & taken:
            found.append((node["id"], leaves))
        return leaves

    walk(tree)
    assert found, "no selectable cluster of 2–8 behaviours"
    return found[0]


@pytest.mark.slow  # 1,000 Hopper behaviours (test_chart_focus has a 1,000 round in GridWorld)
def test_a_round_of_1000_behaviours_with_clips_on_demand(own_server: Any, page: Any, ui: Any):
    sid = own_server.new_session("groupwise", pool_size=N, frame_size=32, render_workers=2)
    clips: dict[str, int] = {}
    page.on(
        "response",
        lambda r: clips.__setitem__(r.url, r.status) if "/clips/" in r.url else None,
    )
    ui.open_round(own_server, sid, N)

    # Select a cluster: its clips fill group A, are rendered on demand and play.
    node_a, leaves_a = _cluster(own_server, sid, set())
    ui.click_arc(node_a)
    expect(page.locator(".group-A .clip")).to_have_count(len(leaves_a))
    group_videos = page.locator(".group-A video")
    for i in range(len(leaves_a)):
        group_videos.nth(i).evaluate(
            f"(v) => new Promise((ok) => {{ const f = {READY}; if (f(v)) ok(); "
            "else v.addEventListener('loadeddata', () => ok(), { once: true }); })"
        )

    # Hover a leaf in no group: the preview's video gets its clip URL and reaches its data.
    leaf = next(f"b{i}" for i in range(N // 2, N) if f"b{i}" not in leaves_a)
    page.mouse.move(*ui.point_in(leaf))
    preview = page.locator(".preview video")
    expect(preview).to_have_count(1)
    expect(preview).to_have_attribute("aria-label", f"clip of behaviour {leaf}")
    hovered = "document.querySelector('.preview video')"
    page.wait_for_function(f"() => {hovered} && ({READY})({hovered})", timeout=60_000)
    page.mouse.move(2, 2)
    expect(preview).to_have_count(0)

    # A second cluster into B (Alt-click), then answer: the judgement is stored.
    node_b, leaves_b = _cluster(own_server, sid, set(leaves_a))
    ui.click_arc(node_b, modifiers=("Alt",))
    expect(page.locator(".group-B .clip")).to_have_count(len(leaves_b))
    page.mouse.move(3, 400)
    page.keyboard.press("ArrowLeft")
    expect(page.locator(".toast")).to_contain_text("Saved: left better")
    [judgement] = own_server.judgements(sid, 0)
    assert (judgement["left"], judgement["right"]) == (leaves_a, leaves_b)
    assert judgement["label"] == "left" and judgement["source"] == "explored"

    # Lazily: only the clips in view were asked for, and every one was served.
    videos = [url for url in clips if url.endswith(".mp4")]
    assert len(videos) <= 2 * 8 + 1 + 3 + 16, videos  # groups, a hover, medoids, a suggestion
    assert set(clips.values()) <= {200, 206}, clips
    assert page.locator("video").count() <= 2 * 8 + 3
