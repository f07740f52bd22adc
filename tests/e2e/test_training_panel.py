"""The training panel tells what PPO does (issue 39): its step counter moves rollout by
rollout while PPO runs (not only on a refit or an evaluation), Pause stops it, and the
learning chart names its axes with their units. Screenshot: training-panel.png."""

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
    # 256-step rollouts on GridWorld: a few a second on a busy machine
    "research": {"ppo": {"n_envs": 1, "n_steps": 256, "batch_size": 64, "n_epochs": 1}},
}
COUNTER = ".training-steps"


def _steps(page: Page) -> int:
    return int(page.locator(COUNTER).inner_text().split(" ")[0].replace(",", ""))


def _counts_over(page: Page, seconds: float) -> list[int]:
    """The counter's distinct values, read every 0.1 s for `seconds`."""
    seen: list[int] = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        value = _steps(page)
        if not seen or value != seen[-1]:
            seen.append(value)
        time.sleep(0.1)
    return seen


def test_the_step_counter_moves_while_ppo_runs_and_the_chart_names_its_axes(
    server: Server, page: Page, shot: Any
) -> None:
    sid = server.new_session("groupwise", **CONTINUOUS)
    server.wait_phase(sid, "ready", round_index=0)
    page.goto(f"{server.url}/?session={sid}")
    expect(page.locator(".arc.leaf")).to_have_count(16)
    panel = page.get_by_role("region", name="The agent learning")
    button = page.get_by_role("button", name="Group A (left) is better")
    expect(button).to_be_enabled()
    button.click()
    expect(page.locator(".toast")).to_contain_text("Saved")
    expect(panel.locator(COUNTER)).to_have_text(re.compile(r"^[\d,]+ PPO steps$"))
    page.wait_for_function(
        "(sel) => !document.querySelector(sel).textContent.startsWith('0 ')",
        arg=COUNTER,
        timeout=60_000,
    )
    # one answer: one refit, and evaluations at most every 5 s of training; the counter
    # moves far more often, a point at most every second after a rollout
    seen = _counts_over(page, 6.0)
    assert len(seen) >= 4 and seen == sorted(seen), seen

    # the chart's axes say what they show, in the true return's unit (GridWorld has no target)
    expect(panel.locator("circle.curve-point").first).to_be_attached(timeout=60_000)
    expect(panel.locator("text.axis-label.y")).to_have_text("true return")
    expect(panel.locator("text.axis-label.x")).to_have_text("session time (m:ss)")
    ticks = panel.locator("text.tick.x").all_text_contents()  # SVG text has no innerText
    assert ticks and len(ticks) == len(set(ticks)), ticks  # never "0:00 0:00 0:00 0:00"
    # no line of the panel is cut off
    cut = page.evaluate(
        "() => [...document.querySelectorAll('.training-text p')]"
        ".filter((p) => !p.hidden && p.scrollWidth > p.clientWidth + 1).map((p) => p.textContent)"
    )
    assert cut == [], cut
    shot(page, "training-panel")

    # Pause pauses PPO: the counter stands still until the round resumes
    page.get_by_role("button", name="Pause the round timer").click()
    expect(page.get_by_role("button", name="Resume the round timer")).to_be_visible()
    time.sleep(1.5)  # a slice in flight and its point land
    paused = _counts_over(page, 3.0)
    assert len(paused) == 1, paused
    summary = server.api("GET", f"/api/sessions/{sid}/training")["summary"]
    time.sleep(2.0)
    again = server.api("GET", f"/api/sessions/{sid}/training")["summary"]
    assert again["ppo_steps"] == summary["ppo_steps"]
    page.get_by_role("button", name="Resume the round timer").click()
    page.wait_for_function(
        "([sel, n]) => Number(document.querySelector(sel).textContent"
        ".split(' ')[0].replaceAll(',', '')) > n",
        arg=[COUNTER, paused[0]],
        timeout=60_000,
    )


def test_the_new_session_forms_training_section_says_what_each_setting_does_in_its_mode(
    server: Server, page: Page
) -> None:
    page.goto(f"{server.url}/?new")
    expect(page.get_by_role("heading", name="New session")).to_be_visible()
    section = page.get_by_role("group", name="Training", exact=True)
    mode = section.get_by_label("Training", exact=True)
    expect(mode).to_have_value("continuous")  # the default, in the visible Training section
    help_of = section.locator("#setting-training-help")
    expect(help_of).to_contain_text("PPO trains while you compare")
    steps = section.locator("#setting-ppo_steps_per_round-help")
    expect(steps).to_contain_text("Not used in continuous training")
    mode.select_option("rounds")
    expect(steps).to_contain_text("PPO env steps after each round")
    expect(help_of).to_contain_text("PPO trains after each round ends")
    for text in section.locator(".help").all_inner_texts():
        assert not text.rstrip().endswith(":"), text  # never cut at a colon
