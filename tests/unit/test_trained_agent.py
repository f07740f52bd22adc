"""A `groupwise train` run continued with more steps on the frozen reward, packed as
agent.zip and loaded back with `load_agent` (docs/library.md)."""

import zipfile

import numpy as np
import pytest

import groupwise
from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig
from groupwise.run.agent_package import measure_of
from groupwise.run.final import continue_run
from groupwise.run.headless import run_session

TINY = RunConfig(
    loop=LoopConfig(
        env="GridWorld", comparisons=4, rounds=1, steps=64, final_steps=64, eval_episodes=1
    ),
    reward=RewardConfig(epochs=1, initial_epoch_multiplier=1),
    ppo=PPOConfig(n_envs=1, n_steps=32, batch_size=16, n_epochs=1, tensorboard=False),
)


def test_a_train_run_continues_and_loads_as_an_agent(tmp_path):
    run_session(TINY, tmp_path, show_progress=False)  # round 0, then the final row 1
    records = continue_run(tmp_path, steps=32, frame_size=32, show_progress=False)
    assert [r.round for r in records] == [0, 1, 2]
    assert records[2].comparisons == 0 and np.isnan(records[2].reward_loss)
    assert records[2].env_steps >= records[1].env_steps + 32

    names = set(zipfile.ZipFile(tmp_path / "agent.zip").namelist())
    assert {"README.md", "agent.json", "policy.zip", "vecnormalize.npz", "reward.pt"} <= names
    readme = zipfile.ZipFile(tmp_path / "agent.zip").read("README.md").decode()
    assert "groupwise.load_agent" in readme

    agent = groupwise.load_agent(tmp_path / "agent.zip")
    assert (agent.env, agent.summary.round) == ("GridWorld", 2)
    # the plan's final row and the continuation are rounds without feedback
    assert [r.feedback for r in agent.summary.rounds] == [True, False, False]
    obs, _ = agent.make_env().reset(seed=1)
    assert agent.predict(obs).shape == ()
    assert agent.predict(np.stack([obs] * 4)).shape == (4,)
    assert agent.evaluate(episodes=2, seed=0).shape == (2,)
    assert agent.config() == TINY


def test_continuing_needs_one_of_steps_and_rounds(tmp_path):
    with pytest.raises(ValueError, match="either steps or rounds"):
        continue_run(tmp_path, steps=1, rounds=1)
    with pytest.raises(ValueError, match="simulated decision-maker"):
        continue_run(tmp_path, rounds=1, oracle="human")


@pytest.mark.parametrize(
    ("env", "measure"),
    [
        ("GridWorld", "true return"),
        ("Hopper-backflip", "target score (backward turns)"),
        ("groupwise/Walker2d-splits-v0", "target score (s held)"),
    ],
)
def test_the_summary_names_what_it_measures(env, measure):
    assert measure_of(env) == measure
