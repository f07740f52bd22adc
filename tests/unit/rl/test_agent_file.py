"""The normalisation an agent file records is the one the trained agent applied: a policy
loaded from the file sees the observations PPO saw."""

import dataclasses

import numpy as np

from groupwise.agent_file.summary import FORMAT, AgentSummary
from groupwise.config import PPOConfig
from groupwise.envs import make_env
from groupwise.rl.agent_file import normalisation
from groupwise.rl.ppo import PPOAgent
from groupwise.rl.trained_agent import TrainedAgent


def test_a_loaded_agent_normalises_observations_as_the_trained_one_did():
    cfg = PPOConfig(n_envs=1, n_steps=32, batch_size=16, n_epochs=1, tensorboard=False)
    agent = PPOAgent(lambda: make_env("MountainCarContinuous"), cfg, seed=0)
    agent.learn(64, seed=0)  # the running mean and variance move off 0 and 1
    recorded = normalisation(agent)
    summary = AgentSummary(
        format=FORMAT,
        env="MountainCarContinuous",
        round=0,
        env_steps=64,
        measure="true return",
        true_return_mean=None,
        true_return_std=None,
        rounds=(),
        **dataclasses.asdict(recorded),
    )
    stats = agent.venv.obs_rms
    loaded = TrainedAgent(None, stats.mean, stats.var, summary, {})
    obs = np.array([[-0.5, 0.01], [0.4, -0.06], [-1.2, 0.07]], dtype=np.float32)
    np.testing.assert_allclose(loaded.normalise(obs), agent.venv.normalize_obs(obs), rtol=1e-6)
    assert recorded.normalize_obs

    raw = dataclasses.replace(cfg, normalize_obs=False)
    assert not normalisation(
        PPOAgent(lambda: make_env("MountainCarContinuous"), raw, 0)
    ).normalize_obs
