"""A real database, SQLite in a temporary directory and PostgreSQL (a database of the test
process's throw-away cluster, tests/postgres.py), with a session whose round 0 is open."""

import hashlib
from collections.abc import Callable

import pytest
from tests.postgres import BACKENDS

from groupwise.storage import Database, SessionSettings
from groupwise.storage import sessions as repo
from groupwise.storage.rounds import (
    BehaviourInput,
    GroupSuggestionInput,
    PairInput,
    PreparedRound,
    store_prepared_round,
)

N = 12


def clip_id(i: int, suffix: str) -> str:
    return f"{hashlib.sha256(f'{i}{suffix}'.encode()).hexdigest()}.{suffix}"


def prepared(n: int = N) -> PreparedRound:
    """A hand-made pool of `n` behaviours (true return = index), two suggestions, a queue."""
    return PreparedRound(
        behaviours=tuple(
            BehaviourInput(i, clip_id(i, "mp4"), clip_id(i, "jpg"), float(i)) for i in range(n)
        ),
        suggestions=(
            GroupSuggestionInput(("b0", "b1"), ("b2", "b3"), "m1", "m2", 2.0),
            GroupSuggestionInput(("b4",), ("b5", "b6"), "m3", "m4", 1.0),
        ),
        edges=(PairInput("b0", "b1", 1.0), PairInput("b2", "b3", 0.5)),
        queue=(PairInput("b0", "b1", 3.0), PairInput("b2", "b3", 2.0), PairInput("b4", "b5", 1.0)),
    )


@pytest.fixture(scope="session", params=BACKENDS)
def db_backend(request: pytest.FixtureRequest) -> str:
    """Every storage test runs on SQLite and on PostgreSQL."""
    return str(request.param)


@pytest.fixture
def db(database_url: str) -> Database:
    database = Database(database_url)
    database.create_schema()
    yield database
    database.dispose()


@pytest.fixture
def open_session(db: Database) -> Callable[..., str]:
    """Make a session (mode, settings) with round 0 prepared and open; returns its id."""

    def make(mode: str = "groupwise", **settings: object) -> str:
        with db.write() as s:
            session = repo.create_session(s, "GridWorld", mode, SessionSettings(**settings))
            session_id = session.id
        with db.write() as s:
            assert store_prepared_round(s, session_id, 0, prepared())
        return session_id

    return make
