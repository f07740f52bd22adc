"""groupwise: reinforcement learning from human feedback with interactive groupwise comparison.

The library's public API (docs/library.md); names load on first use, so ``import groupwise``
stays light and the app's extras are needed only for `WebTeacher`:

- the loop: `PreferenceComparisons` (a user's env factory and agent), `LoopConfig`,
  `TeacherConfig`, `RewardConfig`, `PPOConfig`, `RunConfig`, `RoundRecord`, `run_session`
  (the CLI's loop);
- pools and the behaviour space: `BehaviourPool`, `sample_pool`, `Fragment`, `Trajectory`,
  `build_tree`, `TreeConfig`, `group_candidates`, `pool_candidates`, `suggest_groups`,
  `behaviour_id`;
- asking: `Query`, `PairwiseQueries`, `GroupSuggestions`, `InteractiveWalk`;
- answering: `SimulatedTeacher`, `Perception`, `PairwiseTeacher`, `WebTeacher` (a person on
  the app's page), `Feedback` (a strategy and a teacher), `DECISION_MAKERS` (the study's DMs);
- judgements and learning: `Judgement`, `covering_pairs`, `PreferenceDataset`,
  `RewardEnsemble`, `fit`, `LearnedRewardVecEnv`, `PPOAgent`, `SB3Agent`;
- the result: `load_agent` (an ``agent.zip`` from the app or `groupwise train --from-session`)
  → `TrainedAgent` with `predict(obs)` and `evaluate(env, episodes, seed)`.
"""

import importlib
from typing import Any

__version__ = "0.1.0"

_EXPORTS = {
    "PreferenceComparisons": "groupwise.run.preference_comparisons",
    "LoopConfig": "groupwise.config",
    "TeacherConfig": "groupwise.config",
    "RewardConfig": "groupwise.config",
    "PPOConfig": "groupwise.config",
    "RunConfig": "groupwise.config",
    "RoundRecord": "groupwise.run.records",
    "run_session": "groupwise.run.headless",
    "Run": "groupwise.run.run",
    "begin_round": "groupwise.run.round",
    "end_round": "groupwise.run.round",
    "Offer": "groupwise.run.round",
    "BehaviourPool": "groupwise.behaviour.pool",
    "behaviour_id": "groupwise.episodes.ids",
    "sample_pool": "groupwise.pool.sampling",
    "Fragment": "groupwise.episodes.fragments",
    "Trajectory": "groupwise.episodes.fragments",
    "build_tree": "groupwise.behaviour",
    "TreeConfig": "groupwise.behaviour",
    "group_candidates": "groupwise.behaviour",
    "pool_candidates": "groupwise.query.strategies",
    "suggest_groups": "groupwise.query.groups",
    "Query": "groupwise.query.strategies",
    "PairwiseQueries": "groupwise.query.strategies",
    "GroupSuggestions": "groupwise.query.strategies",
    "InteractiveWalk": "groupwise.query.strategies",
    "SimulatedTeacher": "groupwise.teachers",
    "Perception": "groupwise.teachers",
    "PairwiseTeacher": "groupwise.teachers",
    "Feedback": "groupwise.teachers",
    "DECISION_MAKERS": "groupwise.teachers",
    "WebTeacher": "groupwise.worker.web_teacher",
    "Judgement": "groupwise.preferences.judgement",
    "covering_pairs": "groupwise.preferences.pairs",
    "PreferenceDataset": "groupwise.preferences.dataset",
    "RewardEnsemble": "groupwise.reward",
    "fit": "groupwise.reward",
    "LearnedRewardVecEnv": "groupwise.rl.learned_reward",
    "PPOAgent": "groupwise.rl.ppo",
    "SB3Agent": "groupwise.rl.agents",
    "load_agent": "groupwise.rl.trained_agent",
    "TrainedAgent": "groupwise.rl.trained_agent",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'groupwise' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
