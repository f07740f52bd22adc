"""A reward-free target session to its end in the browser (issue 23): one round of a
Hopper-backflip session answered, the final phase, and the results page leads with the
target's episode score in its unit (backward turns, with the threshold), the number the
evaluation computed, and names the per-step score sum (rad/s) apart.
Screenshot: target-session-end.png (1366 × 768)."""

import csv
import json
import re
from typing import Any

import pytest

from groupwise.agent_file.text import format_value, mean_sd

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

FINAL_TIMEOUT_MS = 240_000
# The least that still trains and evaluates: 8 behaviours, one round, 64 PPO steps after it
# and 64 more in the final phase, two evaluation episodes of 1000 steps.
TINY_TARGET = {
    "recipe": "paper",  # no pre-training, no variants: the test stays fast
    "pool_size": 8,
    "rounds": 1,
    "ppo_steps_per_round": 64,
    "final_steps": 64,
    "eval_episodes": 2,
    "research": {
        "ppo": {"n_envs": 1, "n_steps": 64, "batch_size": 32, "n_epochs": 1, "net_arch": [16]},
        "reward": {"epochs": 1, "initial_epoch_multiplier": 1},
    },
}


def _answer_one(page: Page, ui: Any) -> None:
    """The suggested comparison, or the first and last leaf when none is suggested."""
    expect(page.locator(".comparison .origin")).to_contain_text(
        re.compile("Suggested comparison|No suggestions left|Your selection"), timeout=15_000
    )
    if not page.locator(".group-A .clip").count() or not page.locator(".group-B .clip").count():
        leaves = page.eval_on_selector_all(".arc.leaf", "els => els.map(e => e.dataset.id)")
        page.get_by_role("button", name="Clear groups").click()
        ui.click_arc(leaves[0])
        ui.click_arc(leaves[-1], modifiers=("Alt",))
    page.get_by_role("button", name="Group A (left) is better").click()
    expect(page.locator(".toast")).to_contain_text("Saved")


@pytest.mark.slow  # trains and evaluates Hopper-backflip (the heaviest browser test, ~25 s)
def test_a_target_sessions_results_show_its_episode_score_in_its_unit(
    own_server: Server, page: Page, ui: Any, shot: Any
) -> None:
    state = own_server.api(
        "POST",
        "/api/sessions",
        {"env": "Hopper-backflip", "mode": "groupwise", "settings": TINY_TARGET},
    )
    sid = state["id"]
    own_server.wait_phase(sid, "ready", round_index=0)
    page.goto(f"{own_server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(TINY_TARGET["pool_size"])
    _answer_one(page, ui)
    page.get_by_role("button", name="End round").click()
    page.get_by_role("button", name="Click again to end the round").click()

    results = page.get_by_role("region", name="Session results")
    expect(results).to_be_visible(timeout=FINAL_TIMEOUT_MS)

    # what the evaluation computed: agent.json beside the zip, and rounds.csv's last row
    directory = own_server.data / "sessions" / sid
    summary = json.loads((directory / "agent.json").read_text())
    last = list(csv.DictReader((directory / "rounds.csv").open()))[-1]
    score, sd = summary["target_score_mean"], summary["target_score_std"]
    assert (score, sd) == (float(last["target_score_mean"]), float(last["target_score_std"]))
    assert summary["target"]["unit"] == "backward turns"
    assert summary["measure"] == "per-step score sum (rad/s)"

    expect(page.locator(".score-label")).to_have_text("Backward turns per episode")
    expect(page.locator(".score-value")).to_have_text(mean_sd(score, sd))
    expect(page.locator(".score-goal")).to_have_text("(threshold 1 · stretch 2)")
    per_step = mean_sd(summary["true_return_mean"], summary["true_return_std"])
    expect(page.locator(".score-detail")).to_contain_text(f"Per-step sum {per_step}")
    expect(page.locator(".score-detail")).to_contain_text("rad/s")
    expect(page.locator(".score-detail")).to_contain_text("2 evaluation episodes after round 1")
    video_score = format_value(summary["video"]["target_score"])
    expect(page.locator(".agent-caption")).to_contain_text(f"backward turns {video_score}")
    expect(page.locator(".agent-caption")).to_contain_text("rad/s")
    results = page.get_by_role("region", name="Session results")
    expect(results.locator(".chart-title").first).to_have_text(
        "Backward turns per episode, per round"
    )
    # the session's learning curve is of the per-step sum, and says so
    expect(page.locator(".learning-title")).to_have_text(
        "Per-step score sum (rad/s) over the session"
    )
    expect(page.locator(".return-chart line.threshold")).to_have_count(1)
    expect(page.locator(".return-chart circle.point")).to_have_count(2)
    expect(results).not_to_contain_text("target score")
    shot(page, "target-session-end")
