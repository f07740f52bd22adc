"""Session rows (cascades, lookup, resumable sessions) and the database's pragmas and
schema upgrades, on real SQLite and PostgreSQL databases."""

import sqlite3

import pytest
from sqlalchemy import delete, func, select, text

from groupwise.storage import Database, NotFoundError
from groupwise.storage.database import add_missing_columns, sqlite_url
from groupwise.storage.judging import JudgementInput, add_judgement
from groupwise.storage.models import JudgementRow, PairRow, SessionRow
from groupwise.storage.sessions import find_resumable, get_session, list_sessions


@pytest.mark.parametrize("db_backend", ["sqlite"])
def test_sqlite_runs_in_wal_mode_with_foreign_keys(db):
    with db.read() as s:
        assert s.execute(text("PRAGMA journal_mode")).scalar() == "wal"
        assert s.execute(text("PRAGMA foreign_keys")).scalar() == 1
        assert s.execute(text("PRAGMA busy_timeout")).scalar() > 0


ADVISORY_LOCKS = text(
    "SELECT count(*) FROM pg_locks WHERE locktype = 'advisory' AND pid = pg_backend_pid()"
)


@pytest.mark.parametrize("db_backend", ["postgresql"])
def test_postgresql_writes_hold_the_one_write_lock_and_reads_do_not(db):
    with db.write() as s:
        assert s.execute(ADVISORY_LOCKS).scalar() == 1
    with db.read() as s:
        assert s.execute(ADVISORY_LOCKS).scalar() == 0


def test_deleting_a_session_cascades_to_its_judgements_and_pairs(db, open_session):
    sid = open_session()
    with db.write() as s:
        add_judgement(s, sid, JudgementInput("c", 0, ("b1",), ("b2",), "left", "explored"))
    with db.write() as s:
        s.execute(delete(SessionRow).where(SessionRow.id == sid))
    with db.read() as s:
        assert s.scalar(select(func.count()).select_from(JudgementRow)) == 0
        assert s.scalar(select(func.count()).select_from(PairRow)) == 0


def test_an_older_database_gains_the_new_nullable_columns(tmp_path):
    path = tmp_path / "old.db"
    with sqlite3.connect(path) as old:  # the rounds table as an earlier version made it
        old.execute(
            "CREATE TABLE rounds (id INTEGER PRIMARY KEY, session_id VARCHAR(32), "
            '"index" INTEGER, phase VARCHAR(16), pool_dir TEXT, opened_at DATETIME, '
            "closed_at DATETIME, close_reason VARCHAR(32), stats JSON)"
        )
        old.execute("INSERT INTO rounds (id, session_id, phase) VALUES (1, 's-1', 'closed')")
    database = Database(sqlite_url(path))
    try:
        database.create_schema()
        assert add_missing_columns(database.write_engine) == []  # idempotent
        with database.read() as s:
            assert s.execute(text("SELECT id, shown_at FROM rounds")).all() == [(1, None)]
    finally:
        database.dispose()


def test_unknown_sessions_and_resumable_ones(db, open_session):
    with pytest.raises(NotFoundError, match="no session 's-nope'"), db.read() as s:
        get_session(s, "s-nope")
    older, newer = open_session(), open_session()
    with db.read() as s:
        assert find_resumable(s, "GridWorld", "groupwise").id == newer
        assert find_resumable(s, "GridWorld", "pairwise") is None
        assert [row.id for row in list_sessions(s)] == [newer, older]
