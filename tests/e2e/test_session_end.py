"""The end of a session in the browser: answer a round → "Finish now" → the final training
on the frozen reward model → the agent's video plays, its chart shows each round, its zip
downloads and loads with `groupwise.load_agent`; "Continue training" trains it again.
Screenshot: session-end.png (1366 × 768)."""

from typing import Any

import numpy as np
import pytest

import groupwise

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

POOL = 16
FINAL_TIMEOUT_MS = 180_000
# Real (tiny) training: PPO after the round, a final phase, and a true return to chart.
TRAINING = {
    "rounds": 2,
    "ppo_steps_per_round": 64,
    "final_steps": 128,
    "eval_episodes": 1,
    "research": {
        "ppo": {"n_envs": 1, "n_steps": 64, "batch_size": 32, "n_epochs": 1, "net_arch": [16]},
        "reward": {"epochs": 1, "initial_epoch_multiplier": 2},
    },
}


def _answer_one(page: Page, ui: Any, server: Server, sid: str) -> None:
    """One judgement: the suggested groups, or two leaves chosen in the chart."""
    ui.settled()
    if not page.locator(".group-A .clip").count() or not page.locator(".group-B .clip").count():
        leaves = server.leaves(sid)
        page.get_by_role("button", name="Clear groups").click()
        ui.click_arc(leaves[0])
        ui.click_arc(leaves[-1], modifiers=("Alt",))
    page.get_by_role("button", name="Group A (left) is better").click()
    expect(page.locator(".toast")).to_contain_text("Saved")


def _video_plays(page: Page) -> None:
    page.wait_for_function(
        """() => {
            const v = document.querySelector('video.agent-video');
            return v && v.readyState >= 2 && v.currentTime > 0;
        }""",
        timeout=30_000,
    )


def test_finish_watch_download_and_continue(
    server: Server, page: Page, ui: Any, shot: Any, tmp_path: Any
) -> None:
    sid = server.new_session("groupwise", **TRAINING)
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(POOL)
    _answer_one(page, ui, server, sid)

    page.get_by_role("button", name="Finish now").click()
    page.get_by_role("button", name="Click again to finish the session").click()

    results = page.get_by_role("region", name="Session results")
    expect(results).to_be_visible(timeout=FINAL_TIMEOUT_MS)
    expect(page.locator(".statusbar .phase")).to_have_text("finished")
    expect(page.locator(".statusbar .round")).to_have_text("Round 1 · final phase")
    _video_plays(page)
    # round 0 after feedback, round 1 PPO on the frozen reward model only
    expect(page.locator(".return-chart circle.point")).to_have_count(2)
    expect(page.locator(".return-chart circle.point.frozen")).to_have_count(1)
    expect(results).to_contain_text("1 comparison")
    expect(page.locator(".agent-caption")).to_contain_text("Round 1 · one greedy episode")
    shot(page, "session-end")

    with page.expect_download() as info:
        page.get_by_role("link", name="Download agent (.zip)").click()
    download = info.value
    assert download.suggested_filename == f"groupwise-agent-{sid}-round-1.zip"
    path = tmp_path / download.suggested_filename
    download.save_as(path)
    agent = groupwise.load_agent(path)
    obs, _ = agent.make_env().reset(seed=0)
    assert np.asarray(agent.predict(obs)).shape == ()  # GridWorld: one discrete action
    assert agent.evaluate(episodes=1).returns.shape == (1,)
    assert [r.feedback for r in agent.summary.rounds] == [True, False]

    page.get_by_role("spinbutton", name="How many more").fill("64")
    page.get_by_role("button", name="Continue training").click()
    expect(page.locator(".return-chart circle.point")).to_have_count(3, timeout=FINAL_TIMEOUT_MS)
    expect(page.locator(".agent-caption")).to_contain_text("Round 2 · one greedy episode")
    _video_plays(page)
    state = server.api("GET", f"/api/sessions/{sid}")
    assert (state["phase"], state["round"]) == ("finished", 2)
