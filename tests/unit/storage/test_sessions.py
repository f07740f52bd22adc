"""Session lifecycle, the round timer and the database's pragmas, on a real SQLite file."""

import sqlite3
from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import delete, func, select, text

from groupwise.storage import ConflictError, Database, NotFoundError, SessionSettings
from groupwise.storage import sessions as repo
from groupwise.storage.database import add_missing_columns, sqlite_url
from groupwise.storage.judgements import JudgementInput, add_judgement
from groupwise.storage.models import JudgementRow, PairRow, SessionRow

T0 = datetime(2030, 1, 1, tzinfo=UTC)


def at(seconds: float) -> datetime:
    return T0 + timedelta(seconds=seconds)


def test_sqlite_runs_in_wal_mode_with_foreign_keys(db):
    with db.read() as s:
        assert s.execute(text("PRAGMA journal_mode")).scalar() == "wal"
        assert s.execute(text("PRAGMA foreign_keys")).scalar() == 1
        assert s.execute(text("PRAGMA busy_timeout")).scalar() > 0


def test_deleting_a_session_cascades_to_its_judgements_and_pairs(db, open_session):
    sid = open_session()
    with db.write() as s:
        add_judgement(s, sid, JudgementInput("c", 0, ("b1",), ("b2",), "left", "explored"))
    with db.write() as s:
        s.execute(delete(SessionRow).where(SessionRow.id == sid))
    with db.read() as s:
        assert s.scalar(select(func.count()).select_from(JudgementRow)) == 0
        assert s.scalar(select(func.count()).select_from(PairRow)) == 0


def test_the_timer_counts_only_while_running(db, open_session):
    sid = open_session(round_seconds=100)
    with db.write() as s:  # restart the timer at a known time
        session = repo.get_session(s, sid)
        session.timer_started_at = at(0)
    with db.write() as s:
        repo.pause(s, sid, now=at(30))
    with db.read() as s:
        session = repo.get_session(s, sid)
    assert session.paused and repo.elapsed(session, at(500)) == 30
    assert not repo.round_due(session, at(500))
    with db.write() as s:
        repo.resume(s, sid, now=at(1000))
    with db.read() as s:
        session = repo.get_session(s, sid)
    assert repo.elapsed(session, at(1060)) == 90
    assert not repo.round_due(session, at(1069))
    assert repo.round_due(session, at(1070))
    with db.write() as s:
        assert not repo.close_if_due(s, sid, now=at(1069))
        assert repo.close_if_due(s, sid, now=at(1071))
    with db.read() as s:
        session = repo.get_session(s, sid)
        closed = repo.get_round(s, sid, 0)
    assert session.phase == repo.TRAINING and closed.close_reason == "time"
    assert repo.elapsed(session, at(5000)) == pytest.approx(101)


def test_the_timer_starts_when_a_page_first_shows_the_round(db, open_session):
    sid = open_session(round_seconds=100)
    with db.read() as s:
        session = repo.get_session(s, sid)
        opened = repo.get_round(s, sid, 0)
    # opened, not shown: three minutes later no time is used and nothing is due
    assert opened.opened_at is not None and opened.shown_at is None
    assert session.timer_started_at is None and not session.paused
    later = opened.opened_at + timedelta(minutes=3)
    assert repo.elapsed(session, later) == 0
    assert not repo.round_due(session, later + timedelta(hours=1))
    with db.write() as s:
        assert repo.show_round(s, sid, 0, now=later).shown_at == later
    with db.write() as s:  # shown again (a reload): the first showing counts
        assert repo.show_round(s, sid, 0, now=later + timedelta(seconds=50)).shown_at == later
    with db.read() as s:
        session = repo.get_session(s, sid)
    assert repo.elapsed(session, later + timedelta(seconds=30)) == 30
    assert not repo.round_due(session, later + timedelta(seconds=99))
    assert repo.round_due(session, later + timedelta(seconds=100))


def test_a_round_paused_before_it_is_shown_starts_on_resume(db, open_session):
    sid = open_session(round_seconds=100)
    with db.write() as s:
        repo.pause(s, sid, now=at(0))
    with db.write() as s:
        repo.show_round(s, sid, 0, now=at(10))
    with db.read() as s:
        session = repo.get_session(s, sid)
    assert repo.elapsed(session, at(500)) == 0
    with db.write() as s:
        repo.resume(s, sid, now=at(600))
    with db.read() as s:
        session = repo.get_session(s, sid)
    assert repo.elapsed(session, at(620)) == 20


def test_only_the_open_round_can_be_shown(db, open_session):
    sid = open_session()
    with pytest.raises(ConflictError, match="round 1 is not open yet; the open round is 0"):
        with db.write() as s:
            repo.show_round(s, sid, 1)
    with db.write() as s:
        repo.end_round(s, sid)
    with pytest.raises(ConflictError, match="training"), db.write() as s:
        repo.show_round(s, sid, 0)


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


def test_no_time_limit_when_the_budget_is_zero(db, open_session):
    sid = open_session(round_seconds=0)
    with db.read() as s:
        session = repo.get_session(s, sid)
    assert not repo.round_due(session, datetime.now(UTC) + timedelta(days=3))


def test_pause_needs_an_open_round(db):
    with db.write() as s:
        sid = repo.create_session(s, "GridWorld", "groupwise", SessionSettings()).id
    with pytest.raises(ConflictError, match="preparing"), db.write() as s:
        repo.pause(s, sid)


def test_training_moves_on_to_the_next_round_then_finishes(db, open_session):
    sid = open_session(rounds=2)
    with db.write() as s:
        repo.end_round(s, sid)
    with db.write() as s:
        assert repo.finish_training(s, sid, 0, "sessions/x/checkpoints/round-0000", {"a": 1})
    with db.read() as s:
        session = repo.get_session(s, sid)
        assert (session.phase, session.round) == (repo.PREPARING, 1)
        assert repo.get_round(s, sid, 0).stats == {"a": 1}
        assert repo.get_round(s, sid, 1).phase == repo.ROUND_PREPARING
    with db.write() as s:  # a late report for a round that moved on changes nothing
        assert not repo.finish_training(s, sid, 0, "x", {})


def test_failure_and_retry(db):
    with db.write() as s:
        sid = repo.create_session(s, "GridWorld", "groupwise", SessionSettings()).id
    with pytest.raises(ConflictError, match="has not failed"), db.write() as s:
        repo.retry(s, sid)
    with db.write() as s:
        assert repo.mark_failed(s, sid, repo.PREPARING, "boom") is not None
    with db.read() as s:
        failed = repo.get_session(s, sid)
    assert (failed.phase, failed.failed_phase, failed.error) == ("failed", "preparing", "boom")
    with db.write() as s:
        repo.retry(s, sid)
    with db.read() as s:
        again = repo.get_session(s, sid)
    assert (again.phase, again.error, again.progress_phase) == ("preparing", None, "queued")


def test_unknown_sessions_and_resumable_ones(db, open_session):
    with pytest.raises(NotFoundError, match="no session 's-nope'"), db.read() as s:
        repo.get_session(s, "s-nope")
    older, newer = open_session(), open_session()
    with db.read() as s:
        assert repo.find_resumable(s, "GridWorld", "groupwise").id == newer
        assert repo.find_resumable(s, "GridWorld", "pairwise") is None
        assert [row.id for row in repo.list_sessions(s)] == [newer, older]
