"""A round of 1,000 behaviours on the page (issue 22, item 6): the chart draws every behaviour,
and clips load lazily — a video only for the clips in the groups and the one a person hovers,
never one per behaviour.

The page is the dev build's demo (web/bench.html?demo=groupwise: the whole app on an in-memory
fake server, built by benchmarks/web_render.py) with clips and posters served as files, so the
test sees every clip request the page makes.
"""

import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from benchmarks.web_render import BENCH_DIST, clip_files, ensure_build, serve

N = 1000


@pytest.fixture(scope="module")
def demo_url() -> Iterator[str]:
    ensure_build()
    with tempfile.TemporaryDirectory() as tmp, serve(BENCH_DIST, clip_files(Path(tmp))) as served:
        url, _ = served
        yield f"{url}/bench.html?demo=groupwise&n={N}&clips=served"


def _clip_of(leaf: str) -> str:
    return f"clip{leaf.removeprefix('b')}.mp4"


def test_a_round_of_1000_behaviours_loads_only_the_clips_asked_for(
    demo_url: str, page: Any, ui: Any
) -> None:
    from playwright.sync_api import expect

    clips: list[str] = []
    page.on("request", lambda r: clips.append(r.url) if r.url.endswith(".mp4") else None)
    page.goto(demo_url)
    expect(page.locator(".chart-svg .arc.leaf")).to_have_count(N)
    page.wait_for_function("document.querySelector('canvas.chart-edges')?.dataset.drawnAt")

    # at load: a video for each clip of the first suggestion's groups, none for the chart
    members = ui.clip_ids("A") + ui.clip_ids("B")
    assert 2 <= len(members) <= 16
    expect(page.locator("video")).to_have_count(len(members))
    asked = {_clip_of(m) for m in members}

    # a hovered behaviour's clip plays in the preview, and is requested then
    leaf = next(f"b{i}" for i in range(N // 2, N) if f"b{i}" not in members)
    with page.expect_request(lambda r: r.url.endswith(f"/clips/{_clip_of(leaf)}")):
        page.mouse.move(*ui.point_in(leaf))
    preview = page.locator(".preview video")
    expect(preview).to_have_count(1)
    expect(preview).to_have_attribute("aria-label", f"clip of behaviour {leaf}")
    asked.add(_clip_of(leaf))

    # leaving the chart unloads it
    page.mouse.move(2, 2)
    expect(preview).to_have_count(0)

    # a cluster clicked into group A brings its clips, and only those
    cluster = page.evaluate(
        """() => [...document.querySelectorAll('.arc.node')].find((e) =>
                 /^cluster of [2-8] behaviours, level \\d+$/.test(e.getAttribute('aria-label'))
               ).dataset.id"""
    )
    before = " ".join(ui.clip_ids("A"))
    ui.click_arc(cluster)
    page.wait_for_function(
        "(before) => [...document.querySelectorAll('.group-A .clip')]"
        ".map((e) => e.dataset.id).join(' ') !== before",
        arg=before,
    )
    # (the pointer now rests on the cluster: its preview plays up to three medoid clips)
    expect(preview).not_to_have_count(0)
    medoids = [
        label.removeprefix("clip of behaviour ")
        for label in preview.evaluate_all("(vs) => vs.map((v) => v.getAttribute('aria-label'))")
    ]
    assert len(medoids) <= 3
    group_a = ui.clip_ids("A")
    in_groups = len(group_a) + len(ui.clip_ids("B"))
    expect(page.locator("video")).to_have_count(in_groups + len(medoids))
    asked |= {_clip_of(m) for m in group_a + medoids}
    requested = {url.rsplit("/", 1)[-1] for url in clips}
    assert requested <= asked, f"clips requested that nobody asked for: {requested - asked}"
    assert len(requested) < 40
