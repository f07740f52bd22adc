"""Stored configurations keep meaning what they meant when they were written."""

import json

from groupwise.config import RewardConfig, RunConfig
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
