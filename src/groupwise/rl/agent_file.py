"""The RL side of the agent file (`groupwise.agent_file`): how a `PPOAgent` normalises its
observations, read from its Stable-Baselines3 `VecNormalize`, for the summary to record."""

from stable_baselines3.common.vec_env import VecNormalize

from groupwise.agent_file.summary import ObsNormalisation
from groupwise.rl.ppo import PPOAgent


def normalisation(agent: PPOAgent) -> ObsNormalisation:
    """`agent`'s observation normalisation: on or off, and its clip and epsilon as its
    `VecNormalize` applies them (`PPOAgent` builds it with SB3's defaults).

    Raises:
        TypeError: the agent's env is not wrapped in a `VecNormalize`.
    """
    norm = agent.venv
    if not isinstance(norm, VecNormalize):
        raise TypeError(f"the agent's env is a {type(norm).__name__}, not a VecNormalize")
    return ObsNormalisation(
        normalize_obs=bool(norm.norm_obs),
        clip_obs=float(norm.clip_obs),
        epsilon=float(norm.epsilon),
    )
