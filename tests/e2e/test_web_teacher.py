"""A person in a user's own loop: a `PreferenceComparisons` over the user's SB3 PPO, taught
through the running app's page by `WebTeacher`. The loop publishes a round, the browser
answers a suggested comparison and ends the round, and the loop learns from that judgement.
Screenshot: web-teacher.png."""

import threading
from typing import Any

import numpy as np
import pytest

import groupwise as gw
from groupwise.envs import make_env

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server


def _users_loop(teacher: gw.WebTeacher, out: dict[str, Any]) -> None:
    """What a user writes: their env, their SB3 PPO on the learned reward, our loop."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    try:

        def make():
            return make_env("GridWorld")

        reward = gw.RewardEnsemble.for_env(make, gw.RewardConfig(), np.random.default_rng(0))
        venv = gw.LearnedRewardVecEnv(DummyVecEnv([make]), reward.mean_reward)
        agent = PPO("MlpPolicy", venv, n_steps=64, batch_size=32, seed=0, device="cpu")
        loop = gw.PreferenceComparisons(
            make,
            agent,
            reward,
            gw.Feedback(gw.GroupSuggestions(), teacher),
            gw.LoopConfig(
                comparisons=16, rounds=1, initial_fraction=1.0, steps=64, eval_episodes=1
            ),
        )
        out["records"] = loop.train()
        out["pairs"] = len(loop.dataset)
    except BaseException as error:
        out["error"] = error
    finally:
        teacher.close()


def test_a_person_teaches_a_users_loop(server: Server, page: Page, shot: Any) -> None:
    teacher = gw.WebTeacher(
        server.data,
        env="GridWorld",
        settings={"pool_size": 32, "frame_size": 64, "render_workers": 1, "rounds": 1},
        poll_s=0.2,
    )
    out: dict[str, Any] = {}
    thread = threading.Thread(target=_users_loop, args=(teacher, out), daemon=True)
    thread.start()
    deadline = 180
    while teacher.session_id is None and thread.is_alive() and deadline > 0:
        thread.join(0.2)
        deadline -= 0.2
    assert teacher.session_id, f"the loop published no round: {out.get('error')}"
    sid = teacher.session_id
    server.wait_phase(sid, "ready", round_index=0)

    page.goto(server.url + teacher.url_path)
    expect(page.locator(".arc.leaf")).to_have_count(32)  # 2 × the round's comparisons
    # the strategy's first query is the page's suggestion: answer it
    expect(page.locator(".comparison .origin")).to_contain_text("Suggested comparison")
    expect(page.locator(".group-A .clip").first).to_be_visible()
    page.get_by_role("button", name="Group A (left) is better").click()
    expect(page.locator(".statusbar .counts")).to_contain_text("Comparisons1")
    shot(page, "web-teacher")
    end = page.locator(".end-round")
    end.click()
    end.click()

    thread.join(240)
    assert not thread.is_alive(), "the loop did not return after the round ended"
    assert "error" not in out, out.get("error")
    (record,) = out["records"]
    assert record.judgements == 1
    stored = server.judgements(sid, 0)
    assert len(stored) == 1
    assert out["pairs"] == max(len(stored[0]["left"]), len(stored[0]["right"]))
    assert server.api("GET", f"/api/sessions/{sid}")["phase"] == "finished"
