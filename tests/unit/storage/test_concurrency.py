"""Concurrent judgements on SQLite and PostgreSQL: several threads, through two `Database`
objects on one database (as two server processes would be), submit, retry and undo while
another thread ends the round; every invariant of SPEC §6 must hold afterwards. (With
neither the session row lock nor PostgreSQL's write lock, two judgements got one number
there: a UniqueViolation on (session_id, seq).)"""

import threading
from collections import Counter
from dataclasses import dataclass, field

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import selectinload
from tests.unit.storage.conftest import N

from groupwise.preferences.judgement import Judgement
from groupwise.preferences.pairs import judgement_pairs
from groupwise.storage import ConflictError, Database, SessionSettings
from groupwise.storage.judgements import LABELS
from groupwise.storage.judging import JudgementInput, add_judgement, undo_judgement
from groupwise.storage.lifecycle import close_open_round
from groupwise.storage.models import JudgementRow
from groupwise.storage.sessions import get_session

PLANS = 4
"""Distinct streams of judgements; each is sent by two threads at once (a retry racing its
original through another connection)."""
PER_PLAN = 12
CLOSE_AFTER = 60
"""Submissions (of 2 × PLANS × PER_PLAN) after which a thread ends the round, racing the
submissions still coming."""
LAST_AFTER_CLOSE = 3
"""Each plan's last judgements wait until the round is closed (so some are refused)."""


def plan(index: int) -> list[JudgementInput]:
    """A client's judgements: random disjoint groups of 1–3 behaviours, a random label."""
    rng = np.random.default_rng([21, index])
    judgements = []
    for k in range(PER_PLAN):
        m, n = rng.integers(1, 4, size=2)
        picked = [f"b{i}" for i in rng.choice(N, size=m + n, replace=False)]
        label = str(rng.choice(list(LABELS)))
        judgements.append(
            JudgementInput(f"p{index}-{k}", 0, tuple(picked[:m]), tuple(picked[m:]), label,
                           "explored")
        )  # fmt: skip
    return judgements


@dataclass
class Outcome:
    """What one thread was answered."""

    created: list[str] = field(default_factory=list)  # client ids it stored first
    answered: dict[str, int] = field(default_factory=dict)  # client id → judgement id
    refused: list[str] = field(default_factory=list)  # client ids refused (round closed)
    undone: list[int] = field(default_factory=list)  # judgement ids it undid
    undo_refused: list[int] = field(default_factory=list)


def test_concurrent_judgements_keep_every_invariant(db, database_url, open_session):
    sid = open_session(comparisons_per_round=0)
    servers = [Database(database_url), Database(database_url)]
    submitted = Counter[str]()
    counter_lock = threading.Lock()
    half_way, closed = threading.Event(), threading.Event()
    close_revision: list[int] = []
    start = threading.Barrier(2 * PLANS + 1)
    outcomes = [Outcome() for _ in range(2 * PLANS)]

    def client(thread: int) -> None:
        server, outcome = servers[thread % 2], outcomes[thread]
        undoes = thread < PLANS  # one of each plan's two threads undoes every third
        start.wait()
        for k, judgement in enumerate(plan(thread % PLANS)):
            if k == PER_PLAN - LAST_AFTER_CLOSE:
                closed.wait()
            try:
                with server.write() as s:
                    record, created = add_judgement(s, sid, judgement)
            except ConflictError:
                outcome.refused.append(judgement.client_id)
                continue
            finally:
                with counter_lock:
                    submitted["all"] += 1
                    if submitted["all"] >= CLOSE_AFTER:
                        half_way.set()
            outcome.answered[judgement.client_id] = record.id
            if created:
                outcome.created.append(judgement.client_id)
            if undoes and k % 3 == 0:
                try:
                    with server.write() as s:
                        undo_judgement(s, sid, record.id)
                    outcome.undone.append(record.id)
                except ConflictError:
                    outcome.undo_refused.append(record.id)

    def closer() -> None:
        start.wait()
        half_way.wait()
        with servers[1].write() as s:
            close_revision.append(close_open_round(s, sid).revision)
        closed.set()

    errors: list[BaseException] = []

    def reporting(target, *args) -> None:  # a thread's exception fails the test
        try:
            target(*args)
        except BaseException as error:
            errors.append(error)
            closed.set()
            half_way.set()
            start.abort()

    threads = [threading.Thread(target=reporting, args=(client, t)) for t in range(2 * PLANS)]
    threads.append(threading.Thread(target=reporting, args=(closer,)))
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for server in servers:
        server.dispose()
    assert not errors, errors

    with db.read() as s:
        rows = list(
            s.scalars(
                select(JudgementRow)
                .where(JudgementRow.session_id == sid)
                .options(selectinload(JudgementRow.pairs))
                .order_by(JudgementRow.seq)
            )
        )
        session = get_session(s, sid)
        settings = SessionSettings.model_validate(session.settings)
    by_client = {row.client_id: row for row in rows}
    created = [c for outcome in outcomes for c in outcome.created]
    # nothing lost, nothing doubled: one row per judgement stored first by exactly one call
    assert sorted(created) == sorted(by_client) and len(set(created)) == len(created)
    assert len(rows) == len(by_client)
    # both threads of a plan were answered with the same judgement
    for outcome in outcomes:
        for client_id, judgement_id in outcome.answered.items():
            assert by_client[client_id].id == judgement_id
    # refused ones (the round had closed) were stored by neither thread
    refused = {c for outcome in outcomes for c in outcome.refused}
    assert refused and not refused & set(by_client)
    # numbered 0, 1, … in commit order, and the session's counter agrees
    assert [row.seq for row in rows] == list(range(len(rows)))
    assert session.judgement_seq == len(rows)
    # undo: exactly the undos answered before the round closed; the rest refused
    undone = {j for outcome in outcomes for j in outcome.undone}
    assert undone == {row.id for row in rows if row.undone}
    assert {j for outcome in outcomes for j in outcome.undo_refused}.isdisjoint(undone)
    # nothing changed a judgement after the round closed
    assert close_revision and all(row.revision < close_revision[0] for row in rows)
    # each live judgement holds the max(m, n) pairs derived for its place in the round
    for row in rows:
        assert len(row.pairs) == (0 if row.undone else max(len(row.left), len(row.right)))
        if row.undone:
            continue
        index = {name: int(name[1:]) for name in (*row.left, *row.right)}
        expected = judgement_pairs(
            Judgement(
                tuple(index[n] for n in row.left),
                tuple(index[n] for n in row.right),
                LABELS[row.label],
            ),
            settings.pair_derivation,
            settings.pair_oversample,
            seed=settings.seed,
            round_index=0,
            key=row.seq,
        )
        assert [(p.a, p.b, p.label) for p in row.pairs] == [
            (f"b{p.a}", f"b{p.b}", p.label) for p in expected
        ]
