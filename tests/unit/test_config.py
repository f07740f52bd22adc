"""Stored configurations keep meaning what they meant when they were written."""

import dataclasses
import json
from typing import get_args

import pytest
from pydantic import TypeAdapter

from groupwise.config import (
    LoopConfig,
    PPOConfig,
    RewardConfig,
    RunConfig,
    TeacherConfig,
    TrainingConfig,
    TreeConfig,
)
from groupwise.recipes import PPO_PRESETS
from groupwise.storage.settings import SessionSettings


def test_reward_members_see_observation_and_action_unless_told_otherwise():
    assert RewardConfig().use_actions
    assert not RewardConfig(use_actions=False).use_actions


def test_configs_stored_before_use_actions_existed_keep_their_action_inputs():
    stored = json.loads(RunConfig().to_json())
    del stored["reward"]["use_actions"]
    assert RunConfig.from_dict(stored).reward.use_actions

    settings = json.loads(SessionSettings().model_dump_json())
    settings["reward"] = json.loads(RunConfig().to_json())["reward"]  # as stored before issue 38
    del settings["reward"]["use_actions"]
    assert SessionSettings.model_validate(settings).run_config("GridWorld").reward.use_actions
    # a request overriding other reward fields keeps the default inputs
    research = SessionSettings.model_validate({"research": {"reward": {"ensemble_size": 2}}})
    assert research.run_config("GridWorld").reward.use_actions
    observations = SessionSettings.model_validate({"research": {"reward": {"use_actions": False}}})
    assert not observations.run_config("GridWorld").reward.use_actions


@pytest.mark.parametrize(
    "config",
    [RewardConfig, PPOConfig, LoopConfig, TreeConfig, TeacherConfig, TrainingConfig, RunConfig],
)
def test_every_config_field_says_what_it_means(config: type) -> None:
    # the description is the New-session page's help and the OpenAPI schema's
    properties = TypeAdapter(config).json_schema()["properties"]
    assert [f.name for f in dataclasses.fields(config)] == list(properties)
    undocumented = [name for name, schema in properties.items() if not schema.get("description")]
    assert undocumented == []


def _old_layout(config: RunConfig) -> dict:
    """`config` as written before issue 19: the teacher's fields inside "loop"."""
    stored = json.loads(config.to_json())
    teacher = stored.pop("teacher")
    stored["loop"].update(
        noise_sigma=teacher["noise_sigma"],
        interactive_gap=teacher["interactive_gap"],
        interactive_clear=teacher["interactive_clear"],
        teacher_gamma=teacher["gamma"],
        teacher_mistake=teacher["mistake"],
        teacher_skip_quantile=teacher["skip_quantile"],
        teacher_equal_fraction=teacher["equal_fraction"],
    )
    return stored


def test_configs_stored_with_teacher_fields_in_the_loop_read_as_a_teacher_config():
    teacher = TeacherConfig(
        noise_sigma=0.05,
        gamma=0.5,
        mistake=0.2,
        skip_quantile=0.3,
        equal_fraction=0.4,
        interactive_gap=2.0,
        interactive_clear=3.0,
    )
    config = RunConfig(loop=LoopConfig(comparisons=12, seed=3), teacher=teacher)
    stored = _old_layout(config)
    assert "teacher" not in stored and stored["loop"]["teacher_gamma"] == 0.5
    stored["loop"]["oracle"] = stored["loop"].pop("decision_maker")  # its name then

    assert RunConfig.from_dict(stored) == config
    assert RunConfig.from_dict(json.loads(config.to_json())) == config  # the new layout


def test_a_teacher_field_given_under_its_old_and_new_name_is_refused():
    stored = _old_layout(RunConfig())
    stored["teacher"] = {"gamma": 0.5}
    with pytest.raises(ValueError, match="gamma"):
        RunConfig.from_dict(stored)
    # an unknown loop field still fails as before
    stored = json.loads(RunConfig().to_json())
    stored["loop"]["teacher_patience"] = 1
    with pytest.raises(ValueError, match="teacher_patience"):
        RunConfig.from_dict(stored)


def test_configs_stored_with_an_oracle_read_it_as_the_decision_maker():
    """Runs, checkpoints and sessions written before issue 38 named the decision-maker
    "oracle"."""
    config = RunConfig(loop=LoopConfig(decision_maker="groupwise", comparisons=12, seed=3))
    stored = json.loads(config.to_json())
    stored["loop"]["oracle"] = stored["loop"].pop("decision_maker")
    assert RunConfig.from_dict(stored) == config
    assert RunConfig().merged({"loop": {"oracle": "groupwise"}}).loop.decision_maker == "groupwise"
    research = SessionSettings.model_validate({"research": {"loop": {"oracle": "human"}}})
    assert research.run_config("GridWorld").loop.decision_maker == "human"

    stored["loop"]["decision_maker"] = "pairwise"
    with pytest.raises(ValueError, match=r"loop\.decision_maker is given twice"):
        RunConfig.from_dict(stored)


def test_configs_of_removed_mechanisms_load_without_them(caplog):
    """Runs written before issues 38 and 41 carry the fields of 11 mechanisms that measured
    no gain; they still load, and a warning names a removed mechanism the run actually used."""
    stored = json.loads(RunConfig(loop=LoopConfig(pool_variants=8)).to_json())
    stored["loop"] |= {"pool_variants_greedy": False, "pool_lookahead": 0}
    stored["reward"] |= {"exploration_bonus": 0.0, "pessimism": 0.0, "exploration_decay": 0.5}
    stored["training"] |= {"continue_from": "last", "continue_episodes": 3}
    stored["reward"] |= {"reset_every": None, "reset_margin": None, "crops": 0}
    stored["reward"]["pseudo_labels"] = None
    stored["loop"]["coverage_share"] = 0.0
    with caplog.at_level("WARNING", logger="groupwise.config"):
        assert RunConfig.from_dict(stored) == RunConfig(loop=LoopConfig(pool_variants=8))
    assert not caplog.records  # the defaults: nothing was used
    stored["loop"]["adopt_variants"] = True
    stored["reward"]["pessimism"] = 1.0
    stored["loop"]["coverage_share"] = 0.5
    with caplog.at_level("WARNING", logger="groupwise.config"):
        assert RunConfig.from_dict(stored) == RunConfig(loop=LoopConfig(pool_variants=8))
    (warning,) = caplog.records
    message = warning.getMessage()
    assert "loop.adopt_variants=True, loop.coverage_share=0.5, reward.pessimism=1.0" in message
    assert "Measured and removed" in message


def test_a_partial_config_is_merged_over_the_defaults_section_by_section():
    base = RunConfig(loop=LoopConfig(env="Pendulum-v1", rounds=3))
    merged = base.merged({"loop": {"pool_variants": 8}, "reward": {"ensemble_size": 5}})
    assert merged.loop == LoopConfig(env="Pendulum-v1", rounds=3, pool_variants=8)
    assert merged.reward == RewardConfig(ensemble_size=5) and merged.ppo == base.ppo
    assert base.merged(json.loads(merged.to_json())) == merged  # a whole config replaces all
    assert base.merged({}) == base
    assert base.merged({"loop": {"noise_sigma": 0.5}}).teacher.noise_sigma == 0.5  # old layout
    for partial, field in (({"loop": {"rounds": 0}}, "rounds"), ({"lop": {}}, "lop")):
        with pytest.raises(ValueError, match=field):
            base.merged(partial)
    with pytest.raises(ValueError, match="a config is a JSON object"):
        base.merged([("loop", {})])  # type: ignore[arg-type]  # what a JSON list would be


def test_sessions_stored_with_the_whole_ppo_and_reward_configs_keep_running_as_they_did(caplog):
    """Settings stored before issue 38 held `PPOConfig` and `RewardConfig` whole (with the
    fields of removed mechanisms); they load, and make the run config they made then."""
    ppo = PPOConfig(n_envs=1, n_steps=32, batch_size=16, n_epochs=1)
    stored = json.loads(SessionSettings(pool_size=30, seed=4).model_dump_json())
    del stored["research"]
    stored["ppo"] = dataclasses.asdict(ppo)
    stored["reward"] = dataclasses.asdict(RewardConfig(ensemble_size=2)) | {
        "exploration_bonus": 0.0,
        "pessimism": 0.0,
        "exploration_decay": 0.5,
    }
    stored["reward"]["lr"] = None  # older still: None meant "the default"
    settings = SessionSettings.model_validate(stored)
    cfg = settings.run_config("GridWorld")
    assert cfg.ppo == ppo and cfg.reward == RewardConfig(ensemble_size=2)
    assert (cfg.loop.pool_size, cfg.loop.seed) == (30, 4) and not caplog.records
    again = SessionSettings.model_validate_json(settings.model_dump_json())
    assert again.run_config("GridWorld") == cfg  # and so does what it stores now


def test_the_session_settings_are_product_settings_with_one_line_help():
    assert set(SessionSettings.model_fields) >= {"pool_variants", "ppo_preset", "pretrain_steps"}
    assert not set(SessionSettings.model_fields) & {"ppo", "reward"}
    presets = SessionSettings.model_fields["ppo_preset"].annotation  # a Literal or None
    assert set(get_args(get_args(presets)[0])) == set(PPO_PRESETS)
    schema = SessionSettings.model_json_schema()["properties"]
    for name, field in schema.items():
        help_ = field.get("description", "")
        assert 0 < len(help_) <= 120 and "\n" not in help_, name
    mujoco = SessionSettings(ppo_preset="mujoco", pretrain_steps=500, pool_variants=3)
    cfg = mujoco.run_config("GridWorld")
    assert cfg.ppo == PPO_PRESETS["mujoco"] and cfg.training.pretrain_steps == 500
    assert cfg.loop.pool_variants == 3
    with pytest.raises(ValueError, match="ensemble_sise"):
        SessionSettings(research={"reward": {"ensemble_sise": 2}})
