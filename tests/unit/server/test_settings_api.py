"""The New-session page's contract: the envs it offers, the settings a session would store
(`POST /api/settings/resolve`), and creating sessions with exactly the chosen settings."""

import gymnasium as gym
import pytest

ENV_NAMES = ["Hopper", "HalfCheetah", "Walker2d", "Reacher", "MountainCarContinuous", "GridWorld"]
TARGET_NAMES = ["Hopper-backflip", "HalfCheetah-standup", "Walker2d-splits"]
BROKEN = "groupwise-test/Broken-v0"


def _broken(**kwargs: object) -> gym.Env:
    raise gym.error.DependencyNotInstalled("Box9D is not installed")


if BROKEN not in gym.registry:  # an id that is registered but cannot be made here
    gym.register(id=BROKEN, entry_point=_broken, max_episode_steps=100)


def test_envs_are_the_six_then_the_targets_with_what_they_score(client):
    envs = client.get("/api/envs").json()
    assert [e["name"] for e in envs] == ENV_NAMES + TARGET_NAMES
    hopper = envs[0]
    assert (hopper["kind"], hopper["gym_id"], hopper["horizon"]) == (
        "env",
        "groupwise/Hopper-v0",
        1000,
    )
    assert hopper["clip_seconds"] == 1.5 and hopper["target"] is None
    backflip = next(e for e in envs if e["name"] == "Hopper-backflip")
    assert backflip["kind"] == "target" and backflip["clip_seconds"] == 1.5
    assert backflip["target"]["unit"] == "backward turns"
    assert (backflip["target"]["threshold"], backflip["target"]["stretch"]) == (1.0, 2.0)
    assert backflip["target"]["base"] == "Hopper" and backflip["target"]["description"]
    splits = next(e for e in envs if e["name"] == "Walker2d-splits")
    assert splits["target"]["success"] == "a split held ≥ 1 s"  # words, not "s held ≥ 1"


def test_resolve_gives_the_envs_defaults_with_l_in_steps(client):
    hopper = client.post("/api/settings/resolve", json={"env": "Hopper"}).json()
    # 1.5 s of 0.008 s steps; the final phase trains two rounds' worth of PPO steps
    assert (hopper["clip_seconds"], hopper["fragment_length"]) == (1.5, 188)
    assert hopper["final_steps"] == 2 * hopper["ppo_steps_per_round"] == 40_000
    assert hopper["pool_size"] == 100 and hopper["recipe"] == "teach"
    # the teach recipe's parts on a MuJoCo env (recipes.RECIPES)
    assert (hopper["ppo_preset"], hopper["pretrain_steps"], hopper["pool_variants"]) == (
        "mujoco-entropy",
        100_000,
        8,
    )
    assert hopper["research"] is None and "ppo" not in hopper  # the core's configs are not settings
    grid = client.post("/api/settings/resolve", json={"env": "GridWorld"}).json()
    assert (grid["clip_seconds"], grid["fragment_length"]) == (1.0, 30)
    assert (grid["ppo_preset"], grid["pretrain_steps"], grid["pool_variants"]) == ("study", 0, 0)
    assert client.get("/api/sessions").json() == []  # nothing was created


def test_resolve_fills_what_follows_from_the_chosen_settings(client):
    chosen = {"clip_seconds": 2, "ppo_steps_per_round": 5000}
    resolved = client.post(
        "/api/settings/resolve", json={"env": "Hopper-backflip", "settings": chosen}
    ).json()
    assert (resolved["fragment_length"], resolved["final_steps"]) == (250, 10_000)
    steps = client.post(
        "/api/settings/resolve", json={"env": "Hopper", "settings": {"fragment_length": 30}}
    ).json()
    assert (steps["fragment_length"], steps["clip_seconds"]) == (30, None)


def test_resolve_gives_the_chosen_recipes_parts_and_each_part_chosen_on_its_own(client):
    def resolve(settings: dict) -> tuple:
        body = {"env": "Hopper-backflip", "settings": settings}
        got = client.post("/api/settings/resolve", json=body).json()
        return got["recipe"], got["ppo_preset"], got["pretrain_steps"], got["pool_variants"]

    assert resolve({"recipe": "paper"}) == ("paper", "study", 0, 0)
    assert resolve({"pretrain_steps": 5000}) == ("teach", "mujoco-entropy", 5000, 8)
    assert resolve({"recipe": "paper", "ppo_preset": "mujoco"}) == ("paper", "mujoco", 0, 0)


@pytest.mark.parametrize(
    ("env", "settings", "words"),
    [
        ("Bogus-v9", {}, "unknown env 'Bogus-v9'"),
        (BROKEN, {}, "cannot be made here: Box9D is not installed"),
        ("Hopper", {"clip_seconds": 20}, "fixed horizon"),  # 2500 steps of a 1000-step env
        ("Pendulum-v1", {"clip_seconds": 20}, "fixed horizon"),  # 400 steps of 200
        # episodes that end before one behaviour (random: 3-20 steps of 25; issue 23)
        ("InvertedPendulum-v5", {}, "none long enough for one window of 25 steps"),
        ("Hopper", {"fragment_length": 30, "clip_seconds": 1}, "disagree"),
        ("Hopper", {"pool_size": 5000}, "settings.pool_size"),
        # an action noise to hand over at, on an env of discrete actions
        ("GridWorld", {"pretrain_steps": 1000, "teach_log_std": -2}, "has Discrete(5) actions"),
    ],
)
def test_what_the_server_would_refuse_is_one_sentence_and_creates_nothing(
    client, env, settings, words
):
    body = {"env": env, "settings": settings}
    for path in ("/api/settings/resolve", "/api/sessions"):
        response = client.post(path, json=body)
        assert response.status_code == 422, response.text
        assert words in response.json()["detail"]
    assert client.get("/api/sessions").json() == []


def test_a_session_stores_exactly_the_chosen_settings(client):
    chosen = {
        "clip_seconds": 2.0,
        "ppo_steps_per_round": 4096,
        "final_steps": 0,
        "seed": 7,
        "rounds": 3,
        "pair_derivation": "cartesian",
        "pool_variants": 4,
        "pretrain_steps": 2048,
        "ppo_preset": "mujoco",
        "research": {"ppo": {"net_arch": [16]}, "reward": {"ensemble_size": 2}},
    }
    body = {"env": "Hopper-backflip", "mode": "pairwise", "settings": chosen}
    resolved = client.post("/api/settings/resolve", json=body).json()
    created = client.post("/api/sessions", json=body)
    assert created.status_code == 201, created.text
    state = created.json()
    assert (state["env"], state["mode"], state["rounds"]) == ("Hopper-backflip", "pairwise", 3)
    assert state["settings"] == resolved
    assert state["settings"]["fragment_length"] == 250
    assert state["settings"]["research"]["ppo"]["net_arch"] == [16]
    assert state["settings"]["pool_variants"] == 4
    assert client.get(f"/api/sessions/{state['id']}").json()["settings"] == resolved


def test_any_registered_gymnasium_id_makes_a_session(client):
    state = client.post("/api/sessions", json={"env": "Pendulum-v1"})
    assert state.status_code == 201, state.text
    # Pendulum's dt is 0.05 s: the default 1 s behaviour is 20 of its 200 steps
    assert (state.json()["env"], state.json()["settings"]["fragment_length"]) == (
        "Pendulum-v1",
        20,
    )
