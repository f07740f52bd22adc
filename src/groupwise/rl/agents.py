"""What the loop trains: any agent that can learn for some steps and act.

The loop needs two verbs of an agent: `learn(steps, seed, ...)` on the learned reward and
`policy(deterministic)` to sample behaviours and evaluate. `PPOAgent` is ours; `as_agent`
adapts anything with Stable-Baselines3's `learn(total_timesteps)` / `predict(obs)` (an SB3
algorithm built on the user's own env, wrapped in `LearnedRewardVecEnv`), so a user's own
training code plugs into the loop unchanged.
"""

from typing import Any, Protocol, runtime_checkable

import numpy as np

from groupwise.rl.callbacks import ProgressCallback, ProgressFn
from groupwise.rl.policy import Policy
from groupwise.types import FloatArray


@runtime_checkable
class Agent(Protocol):
    """The loop's view of a learner (implemented by `PPOAgent` and `SB3Agent`)."""

    @property
    def num_timesteps(self) -> int: ...

    def learn(
        self,
        steps: int,
        seed: int | None,
        report: ProgressFn | None = None,
    ) -> None:
        """Train at least `steps` env steps; `seed` reseeds and starts fresh episodes, None
        continues those in flight."""
        ...

    def policy(self, deterministic: bool = False) -> Policy: ...


class PredictPolicy:
    """A `Policy` over an object with SB3's `predict(obs, deterministic=...)`.

    `predict` draws from the model's own (torch) generator, not from the loop's `rng`: a
    run with such an agent is reproducible only as far as the model's seeding makes it.
    """

    def __init__(self, model: Any, deterministic: bool) -> None:
        self.model = model
        self.deterministic = deterministic

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray:
        del rng
        out = self.model.predict(obs, deterministic=self.deterministic)
        return np.asarray(out[0] if isinstance(out, tuple) else out)


class SB3Agent:
    """An SB3-style model (`learn(total_timesteps, ...)`, `predict(obs)`) as an `Agent`.

    Each `learn` continues the model's step count (`reset_num_timesteps=False` when the
    model takes it) and reseeds it from the loop's seed when it has `set_random_seed`.
    """

    def __init__(self, model: Any) -> None:
        self.model = model
        self._steps = 0

    @property
    def num_timesteps(self) -> int:
        return int(getattr(self.model, "num_timesteps", self._steps))

    def learn(
        self,
        steps: int,
        seed: int | None,
        report: ProgressFn | None = None,
    ) -> None:
        if steps <= 0:
            return
        if seed is not None and hasattr(self.model, "set_random_seed"):
            self.model.set_random_seed(seed)
        if hasattr(self.model, "get_env"):  # SB3: callbacks and a continued step count
            _quiet_default_logger(self.model)
            self.model.learn(
                total_timesteps=steps,
                callback=ProgressCallback(steps, report),
                reset_num_timesteps=False,
            )
        else:
            self.model.learn(steps)
        self._steps += steps

    def policy(self, deterministic: bool = False) -> Policy:
        return PredictPolicy(self.model, deterministic)


def _quiet_default_logger(model: Any) -> None:
    """Give an SB3 model that logs nowhere a logger that writes nothing.

    Without TensorBoard and without a logger of the user's own, SB3 makes an empty
    ``/tmp/SB3-<time>`` folder on every `learn` call, i.e. one per round. A user's own
    logger (``set_logger``) or TensorBoard folder is left alone.
    """
    if getattr(model, "tensorboard_log", None) is None and not getattr(
        model, "_custom_logger", True
    ):
        from stable_baselines3.common.logger import Logger

        model.set_logger(Logger(folder=None, output_formats=[]))


def as_agent(agent: Any) -> Agent:
    """`agent` itself when it is an `Agent`, else an `SB3Agent` over it.

    Raises:
        TypeError: it has neither the `Agent` verbs nor `learn` and `predict`.
    """
    if isinstance(agent, Agent) and not hasattr(agent, "predict"):
        return agent
    if callable(getattr(agent, "learn", None)) and callable(getattr(agent, "predict", None)):
        return SB3Agent(agent)
    raise TypeError(
        f"{type(agent).__name__} is not an agent: it needs learn(steps) and predict(obs) "
        "(as a Stable-Baselines3 algorithm has), or the groupwise.rl.Agent methods"
    )
