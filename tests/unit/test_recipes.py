"""Teaching recipes (`recipes.RECIPES`, issue 39): "teach" is the default of `train`,
`case-study` and the app's New session, "paper" is SPEC §8's protocol and today's defaults,
each part changeable on its own, and old configs and stored sessions unchanged."""

import argparse
import dataclasses
import json

import pytest

from groupwise.cli import build_parser
from groupwise.commands.arguments import with_recipe
from groupwise.commands.case_study import case_config
from groupwise.config import RunConfig
from groupwise.recipes import DEFAULT_RECIPE, PPO_PRESETS, RECIPES
from groupwise.storage.settings import SessionSettings
from groupwise.study.simulation.profiles import PROFILES


def _args(*argv: str) -> argparse.Namespace:
    return build_parser().parse_args(list(argv))


def _parts(cfg: RunConfig) -> tuple[int, int, float]:
    return cfg.training.pretrain_steps, cfg.loop.pool_variants, cfg.ppo.learning_rate


def test_teach_sets_the_measured_parts_on_mujoco_envs_and_the_papers_elsewhere():
    teach, paper = RECIPES["teach"], RECIPES["paper"]
    assert DEFAULT_RECIPE == "teach"
    hopper = teach.apply(RunConfig(), "Hopper-backflip")
    assert _parts(hopper) == (100_000, 8, 3e-4) and hopper.ppo == PPO_PRESETS["mujoco-entropy"]
    assert not hopper.reward.use_actions  # the observation alone
    assert hopper.training.teach_log_std == -2.0  # σ = e^-2 once pre-training ends
    # PPO's MuJoCo settings, with only the entropy bonus that keeps that noise exploring
    assert hopper.ppo.ent_coef > 0
    assert dataclasses.replace(hopper.ppo, ent_coef=0.0) == PPO_PRESETS["mujoco"]
    assert paper.apply(hopper, "Hopper").reward.use_actions
    assert teach.apply(RunConfig(), "GridWorld") == RunConfig()
    assert teach.apply(RunConfig(), "Pendulum-v1") == RunConfig()
    assert paper.apply(RunConfig(), "Walker2d") == RunConfig()  # the defaults: SPEC §8's
    summary = teach.summary()
    assert "stand-up 5/5, backflip 5/5 seeds at 10 and at 20 minutes" in summary
    assert summary.endswith("docs/results/continuous)") and "\n" not in summary
    other = dataclasses.replace(RunConfig(), reward=dataclasses.replace(RunConfig().reward, lr=1))
    assert teach.apply(other, "Hopper").reward.lr == 1  # only its parts change


def test_train_defaults_to_teach_and_paper_is_todays_defaults():
    base = RunConfig()
    assert _parts(with_recipe(base, _args("train", "--env", "Hopper", "--out", "o"), "Hopper")) == (
        100_000,
        8,
        3e-4,
    )
    paper = _args("train", "--env", "Hopper", "--recipe", "paper", "--out", "o")
    assert with_recipe(base, paper, "Hopper") == RunConfig()
    ppo = _args("train", "--env", "Hopper", "--recipe", "paper", "--ppo", "mujoco", "--out", "o")
    assert _parts(with_recipe(base, ppo, "Hopper")) == (0, 0, 3e-4)


def test_case_study_defaults_to_teach_and_each_part_changes_on_its_own():
    def config(*more: str) -> RunConfig:
        args = _args("case-study", "--target", "hopper-backflip", "--out", "o", *more)
        return case_config(args, {})

    assert _parts(config()) == (100_000, 8, 3e-4)
    assert config().ppo == PPO_PRESETS["mujoco-entropy"]
    paper = config("--recipe", "paper")
    assert _parts(paper) == (0, 0, 2e-3) and paper.ppo == PPO_PRESETS["study"]
    assert _parts(config("--pretrain-steps", "0")) == (0, 8, 3e-4)
    assert _parts(config("--pool-variants", "2", "--ppo", "study")) == (100_000, 2, 2e-3)


def test_the_simulation_study_keeps_the_paper_recipe():
    for profile in PROFILES.values():
        for env in ("Hopper", "GridWorld"):
            cfg = profile.run_config(env, "groupwise", 0)
            assert (cfg.training.pretrain_steps, cfg.loop.pool_variants) == (0, 0)
            assert cfg.ppo == profile.ppo


def test_the_apps_settings_reach_the_run_config():
    teach = SessionSettings().run_config("Hopper")
    assert _parts(teach) == (100_000, 8, 3e-4)
    paper = SessionSettings(recipe="paper").run_config("Hopper")
    assert _parts(paper) == (0, 0, 2e-3) and paper.ppo == PPO_PRESETS["study"]
    mixed = SessionSettings(pretrain_steps=500, ppo_preset="study").run_config("Hopper")
    assert _parts(mixed) == (500, 8, 2e-3)
    assert not teach.reward.use_actions and paper.reward.use_actions
    assert teach.loop.exploration_fraction == paper.loop.exploration_fraction == 0.05
    assert (
        SessionSettings(exploration_fraction=0.25).run_config("Hopper").loop.exploration_fraction
        == 0.25
    )
    assert SessionSettings(reward_inputs="obs-act").run_config("Hopper").reward.use_actions
    stored = SessionSettings().for_env("Walker2d")  # what a new session stores: resolved
    assert (
        stored.pretrain_steps,
        stored.pool_variants,
        stored.ppo_preset,
        stored.reward_inputs,
        stored.exploration_fraction,
        stored.teach_log_std,
    ) == (100_000, 8, "mujoco-entropy", "obs", 0.05, -2.0)
    grid = SessionSettings().for_env("GridWorld")  # the paper's parts: no noise to set
    assert (
        grid.teach_log_std is None and grid.run_config("GridWorld").training.teach_log_std is None
    )
    assert SessionSettings(teach_log_std=-1).run_config("Hopper").training.teach_log_std == -1


def test_a_session_stored_before_recipes_keeps_its_parts():
    old = {"pool_size": 100, "pool_variants": 0, "ppo_preset": "study", "pretrain_steps": 0}
    settings = SessionSettings.stored({**old, "stage_after_s": 60})  # a removed setting too
    assert settings.recipe is None and "stage_after_s" not in settings.model_dump()
    assert _parts(settings.run_config("Hopper")) == (0, 0, 2e-3)
    before = SessionSettings(recipe="paper", exploration_fraction=0.25)  # the app's then
    assert SessionSettings.stored({}).run_config("Hopper") == before.run_config("Hopper")
    new = SessionSettings().for_env("Hopper")
    assert SessionSettings.stored(json.loads(new.model_dump_json())) == new


def test_a_session_stored_before_reward_inputs_keeps_the_action_in_its_reward():
    """Its reward model was built on [obs ; act]: the recipe's "obs" would not load it."""
    before = json.loads(SessionSettings().for_env("Hopper").model_dump_json())
    del before["reward_inputs"]
    settings = SessionSettings.stored(before)
    assert settings.reward_inputs == "obs-act" and settings.recipe == "teach"
    assert settings.run_config("Hopper").reward.use_actions


def test_a_session_stored_without_random_actions_keeps_the_apps_then():
    before = json.loads(SessionSettings().for_env("Hopper").model_dump_json())
    del before["exploration_fraction"]
    assert SessionSettings.stored(before).run_config("Hopper").loop.exploration_fraction == 0.25


def test_an_old_config_json_loads_unchanged(tmp_path):
    old = json.loads(RunConfig().to_json())  # a run of today's defaults, written before recipes
    (tmp_path / "config.json").write_text(json.dumps(old))
    assert RunConfig.load(tmp_path / "config.json") == RunConfig()
    assert RunConfig.load(tmp_path / "config.json").training.pretrain_steps == 0


@pytest.mark.parametrize("recipe", ["bogus", ""])
def test_an_unknown_recipe_is_refused(recipe, capsys):
    with pytest.raises(SystemExit):
        _args("train", "--env", "Hopper", "--recipe", recipe, "--out", "o")
    assert "invalid choice" in capsys.readouterr().err
