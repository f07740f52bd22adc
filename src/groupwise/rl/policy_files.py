"""A policy named on the command line: "random", or a checkpoint directory of a run."""

import dataclasses
from pathlib import Path

from groupwise.config import PPOConfig, RunConfig
from groupwise.envs import make_env
from groupwise.rl.policy import Policy, RandomPolicy


def load_policy(spec: str, env: str, deterministic: bool = False) -> Policy:
    """ "random", or a checkpoint directory (``policy.zip`` + ``vecnormalize.npz``, as
    written by `groupwise train` under ``<out>/checkpoints/round-NNNN/``).

    A checkpoint is loaded with the PPO settings of its run's ``config.json`` when that is
    found two levels up, the defaults otherwise; it acts stochastically unless `deterministic`
    (the greedy policy; a random policy is random either way).

    Raises:
        FileNotFoundError: the directory has no ``policy.zip``.
        ValueError: unknown env, or the checkpoint's spaces do not match the env's.
    """
    if spec == "random":
        probe = make_env(env)
        try:
            return RandomPolicy(probe.action_space)
        finally:
            probe.close()
    from groupwise.rl.ppo import POLICY_FILE, PPOAgent  # torch and SB3 only for a checkpoint

    directory = Path(spec)
    if not (directory / POLICY_FILE).is_file():
        raise FileNotFoundError(f"{directory} is not a checkpoint directory (no {POLICY_FILE})")
    config_file = directory.parent.parent / "config.json"
    ppo = RunConfig.load(config_file).ppo if config_file.is_file() else PPOConfig()
    ppo = dataclasses.replace(ppo, n_envs=1, tensorboard=False)
    agent = PPOAgent(lambda: make_env(env), ppo, seed=0)
    agent.load(directory)
    return agent.policy(deterministic=deterministic)
