"""Who answers (a `Teacher`) apart from what is asked (a `QueryStrategy`), and the two put
together into the loop's source of feedback (`Feedback`)."""

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.preferences.judgement import Judgement
from groupwise.query.strategies import Query, QueryStrategy


class Teacher(Protocol):
    """Answers queries on a pool: a simulated decision-maker, or a person (`WebTeacher`).

    A teacher may skip a query (no judgement) and a person may also answer comparisons of
    their own, so the list is not aligned with `queries`.
    """

    def answer(
        self, pool: BehaviourPool, queries: Sequence[Query], rng: np.random.Generator
    ) -> list[Judgement]: ...


class FeedbackSource(Protocol):
    """What the loop asks for feedback: up to `n_queries` judgements on a pool.

    A skipped comparison uses up its query and yields no judgement, so the list may be
    shorter than `n_queries`.
    """

    def gather(
        self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator
    ) -> list[Judgement]: ...


@dataclass(frozen=True)
class Feedback:
    """A query strategy proposes, a teacher answers: `gather` is the loop's `FeedbackSource`.

    The same generator serves both, strategy first, so a simulated decision-maker's run is
    a function of (pool, n_queries, rng).
    """

    queries: QueryStrategy
    teacher: Teacher

    def gather(
        self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator
    ) -> list[Judgement]:
        return self.ask(pool, n_queries, rng)[1]

    def ask(
        self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator
    ) -> tuple[list[Query], list[Judgement]]:
        """The queries asked and the judgements they yielded (`gather` keeps the latter)."""
        if n_queries <= 0 or len(pool) < 2:
            return [], []
        queries = self.queries.propose(pool, n_queries, rng)
        return queries, self.teacher.answer(pool, queries, rng)
