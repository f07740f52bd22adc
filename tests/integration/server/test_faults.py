"""Fault injection under load, shortened (`python -m benchmarks faults` runs 100 trials):
a real server and its worker are SIGKILLed at random moments while clients submit
judgements; the database must hold every answered judgement once, whole, as sent. In
continuous sessions (the app's default) the worker is killed while it trains PPO, refits,
prepares the next round ahead or commits a round after opening the next. Both databases:
SQLite in both training modes, PostgreSQL (a database of the test process's cluster,
tests/postgres.py) in continuous mode only, to keep it short.

The audit itself is checked on both databases with judgements stored and then damaged by
hand, so that a harness that sees nothing wrong cannot be an audit that sees nothing."""

import pytest
from benchmarks.fault_audit import Ledger, audit, read_only
from benchmarks.faults import FaultConfig, run
from sqlalchemy import text
from sqlalchemy.exc import DBAPIError
from tests.postgres import BACKENDS

from groupwise.storage import Database, SessionSettings
from groupwise.storage import sessions as repo
from groupwise.storage.judging import JudgementInput, add_judgement
from groupwise.storage.rounds import BehaviourInput, PreparedRound, store_prepared_round


@pytest.mark.parametrize(
    ("db_backend", "training"),
    [
        ("sqlite", "continuous"),
        # the other backend and mode in make test-slow (about 45 s each on 2 cores)
        pytest.param("sqlite", "rounds", marks=pytest.mark.slow),
        pytest.param("postgresql", "continuous", marks=pytest.mark.slow),
    ],
)
def test_kills_of_server_and_worker_lose_duplicate_and_half_store_nothing(
    database_url, db_backend, training
):
    config = FaultConfig(
        trials=4, clients=3, seed=1, load_s=(0.2, 1.0), training=training, db=database_url
    )
    outcome = run(config)
    audit = outcome.audit
    assert audit.database.startswith(db_backend), audit.database
    assert min(outcome.kills.values()) > 0, outcome.kills  # seed 1 draws both kinds
    assert audit.acknowledged > 20, audit
    problems = "\n".join(audit.problems + tuple(outcome.failures))
    assert (audit.lost, audit.duplicated, audit.half_stored, audit.altered) == (0, 0, 0, 0), (
        problems
    )
    assert audit.server_errors == 0, problems
    assert audit.orphans == 0, problems
    assert outcome.stuck == 0 and not outcome.failures, problems
    assert outcome.usable_at_end  # the session resumed: one more judgement is taken


def _body(client_id: str, left: list[str], right: list[str]) -> dict:
    return {"client_id": client_id, "round": 0, "left": left, "right": right, "label": "left"}


@pytest.mark.parametrize("db_backend", BACKENDS)
def test_the_audit_finds_a_lost_a_half_stored_and_an_altered_judgement(database_url):
    db = Database(database_url)
    db.create_schema()
    with db.write() as s:
        session_id = repo.create_session(s, "GridWorld", "groupwise", SessionSettings()).id
    with db.write() as s:
        behaviours = tuple(BehaviourInput(i, f"c{i}.mp4", f"p{i}.jpg", None) for i in range(4))
        assert store_prepared_round(s, session_id, 0, PreparedRound(behaviours, (), (), ()))
    ledger = Ledger()
    bodies = [
        _body("whole", ["b0", "b1"], ["b2"]),
        _body("pairless", ["b0"], ["b1", "b2", "b3"]),
        _body("relabelled", ["b3"], ["b0"]),
    ]
    for body in bodies:
        with db.write() as s:
            add_judgement(s, session_id, JudgementInput(**body, source="explored"))
        ledger.sent(body)
        ledger.answered(body["client_id"], 201, "")
    assert audit(database_url, session_id, ledger).problems == ()
    ledger.sent(_body("lost", ["b1"], ["b2"]))
    ledger.answered("lost", 201, "")  # as if the server answered and then forgot it
    with db.write() as s:
        s.execute(
            text(
                "DELETE FROM pairs WHERE judgement_id = "
                "(SELECT id FROM judgements WHERE client_id = 'pairless')"
            )
        )
        s.execute(text("UPDATE judgements SET label = 'right' WHERE client_id = 'relabelled'"))
    db.dispose()

    found = audit(database_url, session_id, ledger)

    assert (found.lost, found.half_stored, found.altered, found.duplicated) == (1, 1, 1, 0)
    assert (found.acknowledged, found.stored, found.sent) == (4, 3, 4)


@pytest.mark.parametrize("db_backend", BACKENDS)
def test_the_audit_cannot_write(database_url):
    db = Database(database_url)
    db.create_schema()
    db.dispose()
    engine = read_only(database_url)
    try:
        with pytest.raises(DBAPIError, match=r"(?i)read-?only"), engine.begin() as connection:
            connection.execute(text("DELETE FROM judgements"))
    finally:
        engine.dispose()
