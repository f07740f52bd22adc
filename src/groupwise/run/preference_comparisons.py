"""groupwise inside someone else's RLHF code: the loop over a user's env and agent.

`PreferenceComparisons` is the library's front door, in the spirit of imitation's class of
the same name: give it an env factory, an agent (any Stable-Baselines3 algorithm, or
anything with `learn(steps)` and `predict(obs)`), a reward ensemble the agent's env is
rewarded by, and the feedback (a query strategy and a teacher: a simulated decision-maker,
or a person through the web page, `WebTeacher`). `train()` runs the rounds of SPEC §3 with
exactly the round function of `groupwise train` and the app (`groupwise.run.round`).

    make = lambda: gym.make("Pendulum-v1")
    reward = RewardEnsemble.for_env(make, RewardConfig(), np.random.default_rng(0))
    agent = PPO("MlpPolicy", LearnedRewardVecEnv(make_vec_env(make, 4), reward.mean_reward))
    loop = PreferenceComparisons(
        make, agent, reward, Feedback(GroupSuggestions(), SimulatedTeacher()),
        LoopConfig(comparisons=60, rounds=3, steps=12_000, fragment_length=20),
    )
    records = loop.train()

See docs/library.md.
"""

from collections.abc import Callable
from typing import Any

from groupwise.config import LoopConfig, RewardConfig, RunConfig
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward import RewardEnsemble
from groupwise.rl.agents import as_agent
from groupwise.rl.rollout import EnvFactory
from groupwise.run.headless import round_plan, run_rounds
from groupwise.run.progress import CallbackList, OnRoundEnd, ProgressBars, RunCallback
from groupwise.run.records import RoundRecord
from groupwise.run.run import Run
from groupwise.teachers.base import Feedback


class PreferenceComparisons:
    """The RLHF loop over a user's env factory, agent, reward ensemble and feedback.

    `loop` sets the budgets (comparisons, rounds, PPO steps, fragment length, seed, pair
    derivation, ...; `loop.env` and `loop.decision_maker` are only labels here); `reward` how the
    ensemble is fitted. The agent must be trained on `reward_model`'s reward (e.g. its env
    wrapped in `LearnedRewardVecEnv(venv, reward_model.mean_reward)`): the loop refits the
    ensemble in place every round, so the agent's env sees the new reward at once.
    """

    def __init__(
        self,
        make_env: EnvFactory,
        agent: Any,
        reward_model: RewardEnsemble,
        feedback: Feedback,
        loop: LoopConfig | None = None,
        reward: RewardConfig | None = None,
    ) -> None:
        cfg = RunConfig(loop=loop or LoopConfig(), reward=reward or reward_model.cfg)
        self.feedback = feedback
        self.run = Run.of(cfg, make_env, reward_model, as_agent(agent))

    @property
    def records(self) -> list[RoundRecord]:
        """One record per finished round (what `groupwise train` writes to rounds.csv)."""
        return self.run.records

    @property
    def dataset(self) -> PreferenceDataset:
        """Every preference pair so far, with its fragments."""
        return self.run.dataset

    def train(
        self,
        show_progress: bool = False,
        on_round: Callable[[RoundRecord], None] | None = None,
    ) -> list[RoundRecord]:
        """Run the rounds not run yet (all of them on a fresh object) and return the records;
        `on_round` hears each finished round."""
        callbacks: list[RunCallback] = [OnRoundEnd(on_round)] if on_round else []
        bars = None
        if show_progress:
            bars = ProgressBars(len(round_plan(self.run.cfg.loop)), self.run.next_round)
            callbacks.append(bars)
        try:
            run_rounds(self.run, self.feedback, CallbackList(callbacks))
        finally:
            if bars is not None:
                bars.close()
        return self.records
