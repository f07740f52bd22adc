"""The page shows the agent learning (issue 24): in a continuous GridWorld session, two
answers start PPO while the round stays open, and the panel under the behaviours shows the
PPO steps growing, the last refit, the pool's age and the true return's chart gaining
points from the event stream; the finished page draws the same curve. Screenshots:
training-curve.png, training-curve-finished.png (1366 × 768)."""

import re
import time
from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

CONTINUOUS = {
    "training": "continuous",
    "eval_episodes": 2,
    "research": {"ppo": {"n_envs": 1, "n_steps": 64, "batch_size": 32, "n_epochs": 1}},
}
"""A rollout of 64 steps takes a few milliseconds; every evaluation two GridWorld episodes."""


def _steps(page: Page) -> int:
    words = page.locator(".training-steps").inner_text()
    return int(words.split(" ")[0].replace(",", ""))


def test_a_continuous_round_shows_ppo_steps_and_the_true_return_growing(
    server: Server, page: Page, shot: Any
) -> None:
    sid = server.new_session("groupwise", **CONTINUOUS)
    server.wait_phase(sid, "ready", round_index=0)
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(16)
    panel = page.get_by_role("region", name="The agent learning")
    expect(panel).to_be_visible()
    expect(panel).to_contain_text("PPO starts with your first answer.")
    for _ in range(2):  # the suggestion the page pre-filled, answered
        button = page.get_by_role("button", name="Group A (left) is better")
        expect(button).to_be_enabled()
        button.click()
        expect(page.locator(".toast")).to_contain_text("Saved")
    expect(panel.locator(".training-steps")).to_have_text(re.compile(r"^[\d,]+ PPO steps$"))
    expect(panel).to_contain_text(re.compile(r"Last refit: \d+ pairs?"))
    expect(panel).to_contain_text(re.compile(r"Pool sampled [\d,]+ PPO steps? ago"))
    # the policy before PPO, evaluated in the worker's evaluator process
    expect(panel.locator("circle.curve-point").first).to_be_attached(timeout=60_000)
    first = _steps(page)
    # the worker evaluates again after a few seconds of training: more steps, more points
    page.wait_for_function(
        "(n) => Number(document.querySelector('.training-steps').textContent"
        ".split(' ')[0].replaceAll(',', '')) > n",
        arg=first,
        timeout=60_000,
    )
    expect(panel.locator("circle.curve-point")).not_to_have_count(1, timeout=30_000)
    steps = _steps(page)
    assert steps > first
    curve = server.api("GET", f"/api/sessions/{sid}/training")
    assert curve["summary"]["ppo_steps"] >= steps
    assert curve["summary"]["pool_age"] == curve["summary"]["ppo_steps"]  # round 0: from 0
    # the header still holds one line beside the panel
    bar = page.locator(".statusbar").bounding_box()
    assert bar is not None and bar["height"] < 60, bar
    shot(page, "training-curve")

    # the finished page draws the same curve, the round's own point added
    page.get_by_role("button", name="Finish now").click()
    page.get_by_role("button", name="Click again to finish the session").click()
    results = page.get_by_role("region", name="Session results")
    expect(results).to_be_visible(timeout=120_000)
    learning = results.locator(".results-learning")
    expect(learning).to_contain_text("True return over the session")
    points = server.api("GET", f"/api/sessions/{sid}/training")["points"]
    evaluated = [p for p in points if p["true_return"] is not None]
    assert points[-1]["round"] == 0 and points[-1]["ppo_steps"] >= steps  # the round's record
    expect(learning.locator("circle.curve-point")).to_have_count(len(evaluated))
    shot(page, "training-curve-finished")


def test_end_round_opens_the_next_round_cut_from_the_latest_rollouts(
    server: Server, page: Page
) -> None:
    """When the person ends a continuous round, the worker cuts the next pool from PPO's
    latest rollouts and opens it (issue 39: fresh pools), then commits the ended round (how
    long that takes on Hopper: `python -m benchmarks fresh_pools`)."""
    sid = server.new_session("groupwise", **CONTINUOUS, rounds=3)
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(16)
    button = page.get_by_role("button", name="Group A (left) is better")
    expect(button).to_be_enabled()
    button.click()
    expect(page.locator(".toast")).to_contain_text("Saved")
    deadline = time.monotonic() + 120
    while (server.api("GET", f"/api/sessions/{sid}/training")["summary"] or {}).get(
        "ppo_steps", 0
    ) < 1400:  # PPO plays into its second 1,000-step episode, the one the pool is cut from
        assert time.monotonic() < deadline, f"PPO did not start\n{server.tail()}"
        time.sleep(0.2)

    page.get_by_role("button", name="End round").click()
    tick = time.monotonic()
    page.get_by_role("button", name="Click again to end the round").click()
    expect(page.locator(".statusbar .round")).to_have_text("Round 1 of 0–2", timeout=60_000)
    expect(page.locator(".arc.leaf")).to_have_count(16)
    waited = time.monotonic() - tick
    print(f"End round → round 1's chart: {waited:.2f} s")
    # round 0 is committed after round 1 opened: its record arrives in the background
    sql = (
        "SELECT count(*) FROM checkpoints c JOIN rounds r ON r.id = c.round_id "
        'WHERE r.session_id = ? AND r."index" = 0'
    )
    deadline = time.monotonic() + 120
    while server.db_rows(sql, sid) != [(1,)]:
        assert time.monotonic() < deadline, f"round 0 was not committed\n{server.tail()}"
        time.sleep(0.5)
    # round 1's pool is of the rollouts PPO played last (its second episode), not of the
    # policy before PPO
    points = server.api("GET", f"/api/sessions/{sid}/training")["points"]
    assert any(p["round"] == 1 and p["pool_steps"] > 0 for p in points), points
