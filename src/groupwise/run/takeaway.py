"""The take-away agent: the round whose greedy policy the teacher prefers (issue 20).

A run's last round is not always its best: case-study runs that learned their target lost
it again a round later (a walker held a 4.8 s split after round 1, 0.8 s after round 2; a
cheetah stood up and sat down after round 1 and barely rose after round 2;
docs/case-studies.md, "Kept once learned"). So after the last round the teacher, not the
round count, decides which policy a run hands over:

    episodes = round_episodes(run_dir, cfg, rounds, n_episodes, rng)   # each round's greedy policy
    choice = choose_round(episodes, teacher, rng)                      # the teacher compares them

Every round's greedy policy plays the same reset seeds; the teacher compares episode e of
round i with episode e of round j for every pair of rounds (a whole episode is one
behaviour, perceived as the teacher perceives any behaviour: a calibrated teacher's noise
is set on this pool of episodes); a round scores the share of its comparisons it won (an
"equal" answer counts half, a skipped one not at all) and the highest share wins, ties to
the later round. A person makes the same choice on the app's results page
(`groupwise.run.agent_package.pick_round`).
"""

import dataclasses
import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.episodes.fragments import Fragment, Trajectory
from groupwise.query.strategies import Query
from groupwise.teachers.base import Teacher

TAKEAWAY_FILE = "takeaway.json"
"""The choice and the teacher's judgements, in the run's directory."""

ChosenBy = Literal["last", "teacher", "person"]


@dataclass(frozen=True)
class TakeawayConfig:
    """How a headless run chooses the policy it hands over."""

    by: Literal["teacher", "last"] = "teacher"
    """"teacher": the round the run's simulated teacher prefers (module docstring); "last":
    the last round's policy, as before issue 20."""
    episodes: int = 3
    """Greedy episodes of each round's policy the teacher compares (the same reset seeds
    for every round); R rounds cost R × episodes episodes and R(R − 1)/2 × episodes
    comparisons."""

    def __post_init__(self) -> None:
        if self.episodes < 1:
            raise ValueError(f"the teacher needs at least one episode a round, got {self.episodes}")


@dataclass(frozen=True)
class RoundVerdict:
    """One comparison of two rounds' episodes: `label` 1.0 when round `left`'s episode was
    preferred, 0.0 when round `right`'s, 0.5 equal, None when the teacher skipped it."""

    left: int
    right: int
    episode: int
    label: float | None


@dataclass(frozen=True)
class TakeawayChoice:
    """Which round's policy a run hands over, and why."""

    round: int
    by: ChosenBy
    rounds: tuple[int, ...]
    """The candidate rounds, ascending."""
    scores: tuple[float, ...]
    """Per candidate, the share of its comparisons it won (nan: none judged)."""
    returns: tuple[float, ...]
    """Per candidate, the mean true return of the episodes the teacher compared (a target
    env: the sum of the per-step scores), for the reader; the teacher saw them with noise."""
    verdicts: tuple[RoundVerdict, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (nan as None)."""
        data = dataclasses.asdict(self)
        data["scores"] = [None if math.isnan(s) else s for s in self.scores]
        data["returns"] = [None if math.isnan(r) else r for r in self.returns]
        return data

    def describe(self) -> str:
        """One line for the CLI, e.g. "take-away agent: round 2 (teacher's choice; won 0.83
        of its comparisons, last round 0.17)"."""
        if self.by == "last" or not self.rounds:
            return f"take-away agent: round {self.round} (the last)"
        won = dict(zip(self.rounds, self.scores, strict=True))
        last = self.rounds[-1]
        text = f"take-away agent: round {self.round} ({self.by}'s choice; won {won[self.round]:.2f}"
        if self.round != last:
            text += f", last round {won[last]:.2f}"
        return text + " of its comparisons)"


def last_round(rounds: Sequence[int]) -> TakeawayChoice:
    """The last round, chosen by nobody (`TakeawayConfig.by` "last")."""
    last = max(rounds)
    return TakeawayChoice(last, "last", (), (), (), ())


def episode_pool(
    episodes: Mapping[int, Sequence[Trajectory]],
) -> tuple[BehaviourPool, dict[int, tuple[int, ...]]]:
    """The rounds' episodes as one behaviour pool (each whole episode one behaviour) and
    each round's pool indices (round → (E,) indices, in its episodes' order)."""
    fragments: list[Fragment] = []
    members: dict[int, tuple[int, ...]] = {}
    for r in sorted(episodes):
        start = len(fragments)
        for trajectory in episodes[r]:
            fragments.append(
                Fragment(
                    obs=trajectory.obs,
                    acts=trajectory.acts,
                    true_rewards=trajectory.true_rewards,
                    episode=len(fragments),
                    start=0,
                    reset_seed=trajectory.reset_seed,
                )
            )
        members[r] = tuple(range(start, len(fragments)))
    pool = BehaviourPool(
        round=-1, fragments=tuple(fragments), predicted_returns=np.zeros((len(fragments), 1))
    )
    return pool, members


def choose_round(
    episodes: Mapping[int, Sequence[Trajectory]], teacher: Teacher, rng: np.random.Generator
) -> TakeawayChoice:
    """The round whose episodes `teacher` prefers (module docstring); `episodes` maps each
    candidate round to its greedy policy's episodes, episode e of every round from the same
    reset seed. One candidate is chosen without asking.

    Raises:
        ValueError: no candidate, or a round without episodes.
    """
    if not episodes:
        raise ValueError("no round to choose from")
    if any(len(e) == 0 for e in episodes.values()):
        raise ValueError("every candidate round needs at least one episode")
    pool, members = episode_pool(episodes)
    rounds = tuple(sorted(members))
    owner = {index: r for r, indices in members.items() for index in indices}
    queries = [
        Query((members[i][e],), (members[j][e],))
        for i, j in itertools.combinations(rounds, 2)
        for e in range(min(len(members[i]), len(members[j])))
    ]
    answered = {
        (judgement.left[0], judgement.right[0]): judgement.label
        for judgement in (teacher.answer(pool, queries, rng) if queries else [])
    }
    won = dict.fromkeys(rounds, 0.0)
    judged = dict.fromkeys(rounds, 0)
    verdicts = []
    for query in queries:
        a, b = query.left[0], query.right[0]
        label = answered.get((a, b))
        if label is None and (b, a) in answered:  # a teacher that swapped the sides
            label = 1.0 - answered[(b, a)]
        left, right = owner[a], owner[b]
        verdicts.append(RoundVerdict(left, right, members[left].index(a), label))
        if label is not None:
            won[left] += label
            won[right] += 1.0 - label
            judged[left] += 1
            judged[right] += 1
    scores = tuple(won[r] / judged[r] if judged[r] else math.nan for r in rounds)
    returns = pool.true_returns
    means = tuple(float(returns[list(members[r])].mean()) for r in rounds)
    return TakeawayChoice(
        round=preferred(rounds, scores),
        by="teacher",
        rounds=rounds,
        scores=scores,
        returns=means,
        verdicts=tuple(verdicts),
    )


def preferred(rounds: Sequence[int], scores: Sequence[float]) -> int:
    """The round of the highest score, the later one on a tie; the last round when no round
    was judged (nan scores count as lowest)."""
    best = max(
        zip(rounds, scores, strict=True),
        key=lambda rs: (-math.inf if math.isnan(rs[1]) else rs[1], rs[0]),
    )
    return best[0] if not math.isnan(best[1]) else max(rounds)


def write_choice(out: Path, choice: TakeawayChoice, cfg: TakeawayConfig) -> Path:
    """``takeaway.json`` in `out`: the config and the choice (atomically)."""
    path = out / TAKEAWAY_FILE
    partial = path.with_name(f".{path.name}.partial")
    partial.write_text(
        json.dumps({"config": dataclasses.asdict(cfg), **choice.to_dict()}, indent=1) + "\n"
    )
    partial.replace(path)
    return path


def read_choice(out: Path) -> TakeawayChoice | None:
    """The choice `write_choice` wrote into `out`, or None when there is none."""
    try:
        data = json.loads((out / TAKEAWAY_FILE).read_text())
    except FileNotFoundError:
        return None
    return TakeawayChoice(
        round=data["round"],
        by=data["by"],
        rounds=tuple(data["rounds"]),
        scores=tuple(math.nan if s is None else s for s in data["scores"]),
        returns=tuple(math.nan if r is None else r for r in data["returns"]),
        verdicts=tuple(RoundVerdict(**v) for v in data["verdicts"]),
    )
