"""The New-session page (`/?new`): every session setting with the chosen env's defaults, the
case studies' targets, any Gymnasium id typed in (or the server's reason it cannot be), and
a session created with exactly what the form shows. Screenshot: new-session.png.

These tests make sessions of MuJoCo envs, so they run on a server of their own
(`own_server`): the shared server's worker never prepares their pools. They check settings
and never wait for a round.
"""

import re
from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

FORM_VALUES = """() => Object.fromEntries([...document.querySelectorAll('.start-form .setting')]
    .map((row) => row.querySelector('input, select'))
    .map((el) => [el.name, el.type === 'checkbox' ? el.checked : el.value]))"""


def _open_form(page: Page, server: Server) -> None:
    page.goto(f"{server.url}/?new")
    expect(page.get_by_role("heading", name="New session")).to_be_visible()
    # the fields come from the server's schema, filled with the first env's defaults
    expect(page.get_by_label("Pool size", exact=True)).to_have_value("100")


def _shown(text: str | bool, stored: Any) -> bool:
    """Whether an input's text shows a stored value (as the page writes it)."""
    if isinstance(text, bool) or isinstance(stored, str):
        return text == stored
    if stored is None:
        return text == ""
    if isinstance(stored, list):
        return [float(x) for x in text.split(",")] == [float(x) for x in stored]
    return float(text) == float(stored)


def _at(settings: dict[str, Any], key: str) -> Any:
    value: Any = settings
    for part in key.split("."):
        value = value[part]
    return value


def test_an_id_the_server_cannot_make_says_why_and_creates_nothing(
    own_server: Server, page: Page
) -> None:
    before = own_server.api("GET", "/api/sessions")
    _open_form(page, own_server)
    page.get_by_label("Environment").select_option(label="Another Gymnasium id…")
    typed = page.get_by_label("Gymnasium id")
    expect(typed).to_be_focused()
    typed.fill("Bogus-v9")
    typed.press("Tab")
    error = page.locator("#start-env-error")
    expect(error).to_contain_text("unknown env 'Bogus-v9'")
    expect(typed).to_have_attribute("aria-invalid", "true")
    start = page.get_by_role("button", name="Start session")
    expect(start).to_be_disabled()
    assert own_server.api("GET", "/api/sessions") == before

    # a registered Gymnasium id is fine: its defaults fill the form (1 s of 0.05 s steps)
    typed.fill("Pendulum-v1")
    typed.press("Tab")
    expect(error).to_be_hidden()
    expect(page.get_by_label("Fragment length")).to_have_value("20")
    expect(start).to_be_enabled()
    assert own_server.api("GET", "/api/sessions") == before

    # a refused setting is named as the form labels it, not by its place in the body
    page.get_by_label("Pool size", exact=True).fill("1500")
    form_error = page.locator("#start-form-error")
    expect(form_error).to_have_text("Pool size: Input should be less than or equal to 1000")
    assert own_server.api("GET", "/api/sessions") == before


def test_a_target_env_with_chosen_settings_is_created_as_shown(
    own_server: Server, page: Page, shot: Any
) -> None:
    _open_form(page, own_server)
    # a target's option says in words when its episode succeeds
    splits = page.locator('#start-env option[value="Walker2d-splits"]')
    expect(splits).to_have_text("Walker2d-splits · success: a split held ≥ 1 s")
    page.get_by_label("Environment").select_option("Hopper-backflip")
    expect(page.locator("#start-env-about")).to_contain_text("backward turns")
    expect(page.locator("#start-env-about")).to_contain_text("success: ≥ 1 backward turn")
    clip = page.get_by_label("Clip seconds")
    expect(clip).to_have_value("1.5")
    expect(page.get_by_label("Fragment length")).to_have_value("188")

    # the server derives what follows from a choice: L in steps, the final phase's steps
    clip.fill("2")
    expect(page.get_by_label("Fragment length")).to_have_value("250")
    page.get_by_label("PPO steps per round").fill("4096")
    expect(page.get_by_label("Final steps")).to_have_value("8192")
    page.get_by_label("Pairwise baseline").check()
    # the recipe says what it measured; its parts follow it, each changeable on its own
    recipe_help = page.locator("#setting-recipe-help")
    expect(recipe_help).to_have_text(
        "Teach (measured: stand-up 5/5, backflip 5/5 seeds at 10 and at 20 minutes of a "
        "simulated person; the splits unmet; docs/results/continuous)"
    )
    expect(page.get_by_label("Pretrain steps")).to_have_value("100000")
    expect(page.get_by_label("Reward inputs")).to_have_value("obs")
    page.get_by_label("Recipe").select_option("paper")  # no pre-training: the test stays fast
    expect(recipe_help).to_contain_text("Paper (measured: ")
    expect(page.get_by_label("Pretrain steps")).to_have_value("0")
    expect(page.get_by_label("Reward inputs")).to_have_value("obs-act")
    page.get_by_label("Pool variants").fill("4")
    page.get_by_label("PPO preset").select_option("mujoco")
    page.get_by_text("Advanced: clips, the worker and shared sessions").click()
    expect(page.get_by_label("Frame size")).to_have_value("240")
    page.get_by_text("Advanced: clips, the worker and shared sessions").click()
    shown = page.evaluate(FORM_VALUES)
    page.evaluate("document.querySelector('.start').scrollTo(0, 0)")
    shot(page, "new-session")

    page.get_by_role("button", name="Start session").click()
    expect(page).to_have_url(re.compile(r"/\?session=s-[0-9a-f]+$"))
    sid = page.url.split("session=")[1]
    state = own_server.api("GET", f"/api/sessions/{sid}")
    assert (state["env"], state["mode"]) == ("Hopper-backflip", "pairwise")
    settings = state["settings"]
    assert (settings["clip_seconds"], settings["fragment_length"]) == (2.0, 250)
    assert (settings["ppo_steps_per_round"], settings["final_steps"]) == (4096, 8192)
    assert (settings["pool_variants"], settings["ppo_preset"]) == (4, "mujoco")
    assert (settings["recipe"], settings["pretrain_steps"]) == ("paper", 0)
    assert settings["reward_inputs"] == "obs-act"
    # exactly what the form showed, every field of it
    assert settings["driver"] == "app"
    differ = {key: (text, _at(settings, key)) for key, text in shown.items()}
    assert {k: v for k, v in differ.items() if not _shown(*v)} == {}
    assert len(shown) >= 20
