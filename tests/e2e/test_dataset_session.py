"""A recorded dataset's labelling session in the browser (issue 42, deliverable 2): a Minari
dataset of Hopper-v5 built here with Minari's DataCollector, named by its directory; the
chart of its windows, one comparison, the session finished (no agent to hand over: the
page says so and offers the judgements) and the judgements downloaded.
Screenshot: dataset-session.png (1366 × 768)."""

import json
from typing import Any

import pytest
from tests.datasets import HOPPER, build_hopper_dataset

expect = pytest.importorskip("playwright.sync_api").expect
pytest.importorskip("minari")
pytest.importorskip("jax")  # Minari's DataCollector needs it (groupwise[dev])
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

POOL = 16
FINAL_TIMEOUT_MS = 120_000


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> str:
    root = tmp_path_factory.mktemp("minari")
    return str(build_hopper_dataset(root, "test/hopper-random-v0", steps=600))


def test_label_a_dataset_and_download_the_judgements(
    own_server: Server, dataset: str, page: Page, ui: Any, shot: Any, tmp_path: Any
) -> None:
    settings = {
        "dataset": dataset,
        "pool_size": POOL,
        "fragment_length": 10,
        "rounds": 1,
        "round_seconds": 0,
        "comparisons_per_round": 0,
        "frame_size": 64,
        "render_workers": 1,
    }
    state = own_server.api("POST", "/api/sessions", {"mode": "groupwise", "settings": settings})
    sid = state["id"]
    assert state["env"] == HOPPER and state["settings"]["ppo_steps_per_round"] == 0
    own_server.wait_phase(sid, "ready", round_index=0)

    page.goto(f"{own_server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(POOL)
    ui.settled()
    leaves = own_server.leaves(sid)
    page.get_by_role("button", name="Clear groups").click()
    ui.click_arc(leaves[0])
    ui.click_arc(leaves[-1], modifiers=("Alt",))
    ui.expect_group("A", [leaves[0]])
    ui.expect_group("B", [leaves[-1]])
    shot(page, "dataset-session")
    page.get_by_role("button", name="Group A (left) is better").click()
    expect(page.locator(".toast")).to_contain_text("Saved")

    page.get_by_role("button", name="Finish now").click()
    page.get_by_role("button", name="Click again to finish the session").click()
    # no agent, so no results page: the session ends with its judgements' download
    expect(page.locator(".statusbar .phase")).to_have_text("finished", timeout=FINAL_TIMEOUT_MS)
    ended = page.get_by_role("status").filter(has_text="Session finished")
    expect(ended).to_contain_text("1 comparisons and 1 preference pairs")
    expect(page.get_by_role("link", name="Download agent (.zip)")).to_have_count(0)

    with page.expect_download() as info:
        page.get_by_role("link", name="Download judgements (JSONL)").click()
    path = tmp_path / "judgements.jsonl"
    info.value.save_as(path)
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    (judgement,) = [row for row in rows if row["type"] == "judgement"]
    assert (judgement["left"], judgement["right"]) == ([leaves[0]], [leaves[-1]])
    assert [(p["a"], p["b"], p["label"]) for p in judgement["pairs"]] == [
        (leaves[0], leaves[-1], 1.0)
    ]
