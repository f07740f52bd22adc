"""Choosing the take-away agent on the results page (issue 20): a 2-round GridWorld session
answered and finished, the results page lists each round's agent with its clip (still until
pointed at) and its true return; a refused pick shows the server's reason; "Take this agent"
on round 0 (from the keyboard) makes round 0 the download: `GET …/agent`, the page's choice,
video and caption, and the zip's name and contents say round 0.
Screenshots: agent-pick-choices.png, agent-pick.png (1366 × 768)."""

import re
import time
from typing import Any

import pytest

import groupwise

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

FINAL_TIMEOUT_S = 240
# Real (tiny) training, so every round has a checkpoint, a clip and a true return: PPO
# after each round of feedback, a final phase (round 2), one evaluation episode each.
TRAINING = {
    "rounds": 2,
    "ppo_steps_per_round": 64,
    "final_steps": 64,
    "eval_episodes": 1,
    "research": {
        "ppo": {"n_envs": 1, "n_steps": 64, "batch_size": 32, "n_epochs": 1, "net_arch": [16]},
        "reward": {"epochs": 1, "initial_epoch_multiplier": 2},
    },
}


def _leaves(node: dict[str, Any]) -> list[str]:
    if not node["children"]:
        return [node["id"]]
    return [leaf for child in node["children"] for leaf in _leaves(child)]


def _answer_and_end(server: Server, sid: str, round_index: int) -> None:
    """One judgement of the round (its first leaf better than its last), then End round."""
    server.wait_phase(sid, "ready", round_index=round_index)
    leaves = _leaves(server.api("GET", f"/api/sessions/{sid}/rounds/{round_index}/tree")["tree"])
    server.api(
        "POST",
        f"/api/sessions/{sid}/judgements",
        {
            "client_id": f"pick-{round_index}",
            "round": round_index,
            "left": [leaves[0]],
            "right": [leaves[-1]],
            "label": "left",
            "source": "explored",
            "seconds": 1,
            "edits": 0,
            "annotator": "",
        },
    )
    server.api("POST", f"/api/sessions/{sid}/end-round")


def _finished(server: Server, sid: str) -> dict[str, Any]:
    deadline = time.monotonic() + FINAL_TIMEOUT_S
    while (state := server.api("GET", f"/api/sessions/{sid}"))["phase"] != "finished":
        assert state["phase"] != "failed", f"{state['error']}\n{server.tail()}"
        assert time.monotonic() < deadline, f"not finished: {state['phase']}\n{server.tail()}"
        time.sleep(0.5)
    return dict(state)


def test_the_person_takes_round_0s_agent(
    server: Server, page: Page, shot: Any, tmp_path: Any
) -> None:
    sid = server.new_session("groupwise", **TRAINING)
    _answer_and_end(server, sid, 0)
    _answer_and_end(server, sid, 1)
    _finished(server, sid)
    before = server.api("GET", f"/api/sessions/{sid}/agent")
    assert (before["round"], before["chosen_by"]) == (2, "last")
    assert [r["round"] for r in before["rounds"]] == [0, 1, 2]
    assert all(r["checkpoint"] and r["video"] for r in before["rounds"]), before["rounds"]

    page.goto(f"{server.url}/?session={sid}")
    results = page.get_by_role("region", name="Session results")
    expect(results).to_be_visible(timeout=30_000)
    picker = results.locator(".results-takeaway")
    cards = picker.get_by_role("listitem")
    expect(cards).to_have_count(3)
    expect(picker.locator(".takeaway-choice")).to_have_text("Chosen: round 2 (last round)")
    card0 = picker.locator('li[data-round="0"]')
    expect(card0).to_contain_text("Round 0")
    expect(card0).to_contain_text(re.compile(r"True return -?[\d.]+"))
    expect(picker.locator('li[data-round="2"]')).to_contain_text("✓ Chosen")
    expect(picker.get_by_role("button", name="Take this agent")).to_have_count(2)
    shot(page, "agent-pick-choices")

    # the clips are still until pointed at, and then only that one plays
    clips = picker.locator("video.takeaway-video")
    expect(clips).to_have_count(3)
    assert page.eval_on_selector_all(
        ".results-takeaway video", "vs => vs.every((v) => v.paused && !v.autoplay)"
    )
    card0.locator(".takeaway-clip").hover()
    page.wait_for_function(
        "() => { const v = document.querySelector('li[data-round=\"0\"] video');"
        " return !v.paused && v.currentTime > 0; }",
        timeout=15_000,
    )
    assert page.eval_on_selector_all(
        ".results-takeaway li:not([data-round='0']) video", "vs => vs.every((v) => v.paused)"
    )
    # from the keyboard: round 1's play button plays its clip until pressed again
    page.mouse.move(5, 5)
    play1 = picker.get_by_role("button", name="Play round 1's clip")
    play1.focus()
    page.keyboard.press("Space")
    expect(play1).to_have_attribute("aria-pressed", "true")
    page.wait_for_function(
        "() => !document.querySelector('li[data-round=\"1\"] video').paused", timeout=15_000
    )
    assert page.eval_on_selector("li[data-round='0'] video", "v => v.paused")
    page.keyboard.press("Space")
    expect(play1).to_have_attribute("aria-pressed", "false")

    # a refused pick says why, and changes nothing
    reason = "round 0's checkpoint has no policy.zip: its policy cannot be packaged"
    page.route(
        "**/agent/round",
        lambda route: route.fulfill(
            status=409, content_type="application/json", body=f'{{"detail": "{reason}"}}'
        ),
    )
    card0.get_by_role("button", name="Take this agent").click()
    expect(picker.get_by_role("alert")).to_have_text(f"Round 0's agent was not taken: {reason}")
    expect(picker.locator(".takeaway-choice")).to_have_text("Chosen: round 2 (last round)")
    page.unroute("**/agent/round")

    # the real pick, from the keyboard
    card0.get_by_role("button", name="Take this agent").focus()
    page.keyboard.press("Enter")
    expect(picker.locator(".takeaway-choice")).to_have_text("Chosen: round 0 (your pick)")
    expect(picker.locator(".takeaway-choice")).to_be_focused()
    expect(picker.get_by_role("alert")).to_be_hidden()
    expect(card0).to_contain_text("✓ Chosen")
    expect(card0.get_by_role("button", name="Take this agent")).to_have_count(0)
    expect(picker.get_by_role("button", name="Take this agent")).to_have_count(2)  # 1 and 2
    expect(page.locator(".agent-caption")).to_contain_text("Round 0 · one greedy episode")
    expect(results.locator(".results-hint")).to_contain_text("The download is round 0's agent")
    expect(page.locator(".return-chart .chosen-ring")).to_have_count(1)
    after = server.api("GET", f"/api/sessions/{sid}/agent")
    assert (after["round"], after["chosen_by"]) == (0, "person")
    assert after["env_steps"] == after["rounds"][0]["env_steps"]
    card0.locator(".takeaway-clip").hover()  # a clip playing in the picture
    shot(page, "agent-pick")

    with page.expect_download() as info:
        page.get_by_role("link", name="Download agent (.zip)").click()
    download = info.value
    assert download.suggested_filename == f"groupwise-agent-{sid}-round-0.zip"
    path = tmp_path / download.suggested_filename
    download.save_as(path)
    agent = groupwise.load_agent(path)
    assert agent.summary.round == 0

    # a reload reads the choice back from the server
    page.reload()
    expect(page.locator(".results-takeaway .takeaway-choice")).to_have_text(
        "Chosen: round 0 (your pick)", timeout=30_000
    )
