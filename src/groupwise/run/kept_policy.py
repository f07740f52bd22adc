"""The policy the person's answers prefer so far, kept beside the one PPO trains (issue 39).

In continuous training PPO follows a reward fitted on the first few pairs. On the
stand-up's seed 1 that reward pulled the pre-trained policy off standing in round 0, and
from then on every fresh pool held only what the policy did then: behaviours that all
score about 0, which the teacher could only call ties (the *tie trap*,
docs/results/continuous). The reward overpaid states nobody had judged, and the fresh
pools never showed them beside what the person had asked for.

So each fresh pool (from round 1 on) holds a share (`TrainingConfig.kept_share`) sampled
from the *kept* policy, the one the person's answers prefer so far, beside what PPO does
now. When the next pool is cut, the reward refitted on those answers scores the round's
two kinds of behaviour, each by its mean reward per step under each ensemble member:

- every member pays the kept policy's behaviours more, and the members' mean pays them more
  than chance would (a one-sided Mann-Whitney test over behaviours, p < `GO_BACK_P`): PPO
  goes back to the kept policy (its networks, optimiser and observation statistics;
  `PPOAgent.load_policy_state`);
- the members' mean pays the fresh ones at least as much: the policy they were cut from
  becomes the kept one;
- else the kept policy stays.

Both kinds were judged in the same round, so the comparison rests on pairs the person gave,
not on the reward's guess about states nobody saw. The members are fitted on the same pairs,
so "every member" alone is a weak test when the two policies play alike: on the backflip it
went back on margins of 0.003 a step (p = 0.83), and a seed that went back on such noise
through the app ended at 0 % (docs/results/continuous, "a margin for going back").

The kept share is the one part of a fresh pool older than a rollout, by design;
`pool.recent.pool_ages` reports its age.

    went = run.kept.choose(run.ppo, run.ensemble, judged_pool, kept_tag(loop), round_index)
    sources = fresh_sources(loop, run.kept.share(run.ppo, loop, cfg.training.kept_share))
"""

import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from scipy.stats import mannwhitneyu

from groupwise.behaviour.pool import BehaviourPool
from groupwise.config import LoopConfig
from groupwise.episodes.fragments import stack_fragments
from groupwise.pool.sources import CurrentPolicy
from groupwise.reward.ensemble import RewardEnsemble
from groupwise.rl.ppo import PolicyState, PPOAgent
from groupwise.types import FloatArray

log = logging.getLogger(__name__)

KEPT_FILE = "kept_policy.pt"
CUT_FILE = "cut_policy.pt"
STEPS_FILE = "kept_policy.json"

GO_BACK_P = 0.05
"""The one-sided Mann-Whitney p below which the kept behaviours count as paid more (`decide`)."""

Choice = Literal["first", "back", "latest", "kept", "none"]
"""What `KeptPolicy.choose` did: kept the first policy, went back to the kept one, kept the
latest judged one, kept the kept one, or had nothing to compare."""


@dataclass(frozen=True, eq=False)
class Played:
    """A policy as it was (`PPOAgent.policy_state`) when PPO had taken `steps` steps."""

    state: PolicyState
    steps: int


class KeptPolicy:
    """The kept policy of a continuous run and the one the latest pool's fresh behaviours
    were cut from (module docstring)."""

    def __init__(self) -> None:
        self.kept: Played | None = None
        self.cut: Played | None = None
        """The policy round `cut_round`'s fresh behaviours were cut from (the kept one itself
        when that pool has no kept share)."""
        self.cut_round = -1

    def choose(
        self,
        agent: PPOAgent,
        ensemble: RewardEnsemble,
        judged: BehaviourPool | None,
        tag: int,
        round_index: int,
    ) -> Choice:
        """At round `round_index`'s cut, before its pool is sampled: compare what the
        `judged` pool's fresh behaviours (tag 0) and kept ones (`tag`) are paid, go back or
        keep (module docstring), and remember the policy the new pool is cut from. A cut
        of the same round again (the app drops a cut made ahead when a judgement is undone)
        decides nothing again."""
        if self.begin(agent, round_index):
            return "first"
        went: Choice = "none"
        again = round_index == self.cut_round
        if judged is not None and not again and judged.round == self.cut_round:
            went = self._decide(agent, ensemble, judged, tag)
        if went == "back":
            self.cut = self.kept
        else:
            self.cut = Played(agent.policy_state(), agent.num_timesteps)
        self.cut_round = round_index
        return went

    def _decide(
        self, agent: PPOAgent, ensemble: RewardEnsemble, judged: BehaviourPool, tag: int
    ) -> Choice:
        fresh_paid = tag_rewards(ensemble, judged, 0)
        kept_paid = tag_rewards(ensemble, judged, tag)
        # a pool cut from the kept policy itself has no kept share: nothing to compare
        if fresh_paid is None or kept_paid is None or self.kept is None or self.cut is None:
            return "none"
        went, p_kept = decide(fresh_paid, kept_paid)
        if went == "back":
            agent.load_policy_state(self.kept.state)
        elif went == "latest":
            self.kept = self.cut
        fresh, kept = fresh_paid.mean(axis=1), kept_paid.mean(axis=1)
        log.info(
            "round %d's pool: its %d fresh behaviours paid %s a step, the kept policy's %d %s "
            "(one-sided Mann-Whitney p = %.3g that the kept ones are paid more): %s "
            "(the kept policy now: %d PPO steps)",
            judged.round,
            fresh_paid.shape[1],
            [round(float(v), 3) for v in fresh],
            kept_paid.shape[1],
            [round(float(v), 3) for v in kept],
            p_kept,
            went,
            self.kept.steps,
        )
        return went

    def begin(self, agent: PPOAgent, round_index: int) -> bool:
        """Keep the policy PPO starts a run's first round (`round_index`) with, unless one
        is kept: True when it was kept now. The headless round 0 keeps it at its cut, the
        app's worker (whose round 0 is cut by a phase job) when its continuous round
        begins; PPO has not stepped in between."""
        if self.kept is not None:
            return False
        self.kept = self.cut = Played(agent.policy_state(), agent.num_timesteps)
        self.cut_round = round_index
        return True

    def share(self, agent: PPOAgent, loop: LoopConfig, share: float) -> CurrentPolicy | None:
        """The kept policy's share of the pool cut now: none when the pool's fresh
        behaviours come from the kept policy itself, or `share` is 0."""
        if share <= 0 or self.kept is None or self.cut is self.kept:
            return None
        policy = agent.snapshot(state=self.kept.state)
        return CurrentPolicy(loop.exploration_fraction, share, policy=policy)

    def sampled(self, tag: int) -> dict[int, int]:
        """The PPO steps of the policy that played the kept share's episodes (`tag`), when the
        pool cut last has one (`pool.recent.pool_ages`)."""
        if self.kept is None or self.cut is self.kept:
            return {}
        return {tag: self.kept.steps}

    def save(self, directory: Path) -> None:
        """Write both policies into `directory` (a checkpoint's); nothing before the first cut."""
        if self.kept is None or self.cut is None:
            return
        self.kept.state.save(directory / KEPT_FILE)
        if self.cut is not self.kept:
            self.cut.state.save(directory / CUT_FILE)
        steps = {"kept": self.kept.steps, "cut": self.cut.steps, "cut_round": self.cut_round}
        (directory / STEPS_FILE).write_text(json.dumps(steps))

    def load(self, directory: Path) -> None:
        """Read what `save` wrote (none there: nothing kept yet)."""
        self.kept = self.cut = None
        self.cut_round = -1
        if not (directory / STEPS_FILE).is_file():
            return
        steps = json.loads((directory / STEPS_FILE).read_text())
        self.kept = Played(PolicyState.load(directory / KEPT_FILE), steps["kept"])
        cut = directory / CUT_FILE
        self.cut = Played(PolicyState.load(cut), steps["cut"]) if cut.is_file() else self.kept
        self.cut_round = steps["cut_round"]


def decide(fresh_paid: FloatArray, kept_paid: FloatArray) -> tuple[Choice, float]:
    """What a round's answers say about the policies its two kinds of behaviour came from,
    given each member's mean reward per step on each fresh (K, N) and kept (K, M) behaviour
    (`tag_rewards`): go back to the kept policy, make the latest judged one the kept one, or
    stay (module docstring); and the one-sided Mann-Whitney p, over behaviours, that the
    members' mean pays the kept ones more."""
    fresh, kept = fresh_paid.mean(axis=1), kept_paid.mean(axis=1)
    p_kept = float(
        mannwhitneyu(kept_paid.mean(axis=0), fresh_paid.mean(axis=0), alternative="greater").pvalue
    )
    if bool(np.all(kept > fresh)) and p_kept < GO_BACK_P:
        return "back", p_kept
    if float(fresh.mean()) >= float(kept.mean()):
        return "latest", p_kept
    return "kept", p_kept


def tag_rewards(ensemble: RewardEnsemble, pool: BehaviourPool, tag: int) -> FloatArray | None:
    """(K, N) each member's mean reward per step on each of `pool`'s N behaviours of source
    `tag` (`BehaviourPool.sources`); None when it has none, or its sources are unknown."""
    if pool.sources is None or not np.any(pool.sources == tag):
        return None
    chosen = [f for f, source in zip(pool.fragments, pool.sources, strict=True) if source == tag]
    obs, acts = stack_fragments(chosen)
    rewards: FloatArray = ensemble.step_rewards(obs, acts).mean(axis=2)
    return rewards
