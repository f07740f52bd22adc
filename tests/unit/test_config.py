"""Stored configurations keep meaning what they meant when they were written."""

import dataclasses
import json

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
from groupwise.storage.settings import SessionSettings


def test_reward_members_see_observation_and_action_unless_told_otherwise():
    assert RewardConfig().use_actions
    assert not RewardConfig(use_actions=False).use_actions


def test_configs_stored_before_use_actions_existed_keep_their_action_inputs():
    stored = json.loads(RunConfig().to_json())
    del stored["reward"]["use_actions"]
    assert RunConfig.from_dict(stored).reward.use_actions

    settings = json.loads(SessionSettings().model_dump_json())
    del settings["reward"]["use_actions"]
    assert SessionSettings.model_validate(settings).reward.use_actions
    # a request overriding other reward fields keeps the default inputs
    assert SessionSettings.model_validate({"reward": {"ensemble_size": 2}}).reward.use_actions
    observations = SessionSettings.model_validate({"reward": {"use_actions": False}})
    assert not observations.reward.use_actions


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
