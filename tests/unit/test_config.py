"""Stored configurations keep meaning what they meant when they were written."""

import json

from groupwise.config import RewardConfig, RunConfig
from groupwise.storage.settings import SessionSettings


def test_reward_members_see_observations_only_unless_asked():
    assert not RewardConfig().use_actions
    assert RewardConfig(use_actions=True).use_actions


def test_configs_stored_before_use_actions_existed_keep_their_action_inputs(tmp_path):
    stored = json.loads(RunConfig().to_json())
    del stored["reward"]["use_actions"]
    assert RunConfig.from_dict(stored).reward.use_actions
    assert not RunConfig.from_dict(json.loads(RunConfig().to_json())).reward.use_actions

    settings = json.loads(SessionSettings().model_dump_json())
    del settings["reward"]["use_actions"]
    assert SessionSettings.from_stored(settings).reward.use_actions
    assert not SessionSettings().reward.use_actions
    # a request that overrides other reward fields gets today's default
    assert not SessionSettings.model_validate({"reward": {"ensemble_size": 2}}).reward.use_actions
