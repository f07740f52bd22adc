"""The round timer: shown time, pauses, the time budget; on a real SQLite file."""

from datetime import UTC, datetime, timedelta

import pytest

from groupwise.storage import ConflictError, SessionSettings
from groupwise.storage.lifecycle import close_if_due, close_open_round
from groupwise.storage.phases import TRAINING
from groupwise.storage.sessions import create_session, get_round, get_session
from groupwise.storage.timer import elapsed, pause, resume, round_due, show_round

T0 = datetime(2030, 1, 1, tzinfo=UTC)


def at(seconds: float) -> datetime:
    return T0 + timedelta(seconds=seconds)


def test_the_timer_counts_only_while_running(db, open_session):
    sid = open_session(round_seconds=100)
    with db.write() as s:  # restart the timer at a known time
        session = get_session(s, sid)
        session.timer_started_at = at(0)
    with db.write() as s:
        pause(s, sid, now=at(30))
    with db.read() as s:
        session = get_session(s, sid)
    assert session.paused and elapsed(session, at(500)) == 30
    assert not round_due(session, at(500))
    with db.write() as s:
        resume(s, sid, now=at(1000))
    with db.read() as s:
        session = get_session(s, sid)
    assert elapsed(session, at(1060)) == 90
    assert not round_due(session, at(1069))
    assert round_due(session, at(1070))
    with db.write() as s:
        assert not close_if_due(s, sid, now=at(1069))
        assert close_if_due(s, sid, now=at(1071))
    with db.read() as s:
        session = get_session(s, sid)
        closed = get_round(s, sid, 0)
    assert session.phase == TRAINING and closed.close_reason == "time"
    assert elapsed(session, at(5000)) == pytest.approx(101)


def test_the_timer_starts_when_a_page_first_shows_the_round(db, open_session):
    sid = open_session(round_seconds=100)
    with db.read() as s:
        session = get_session(s, sid)
        opened = get_round(s, sid, 0)
    # opened, not shown: three minutes later no time is used and nothing is due
    assert opened.opened_at is not None and opened.shown_at is None
    assert session.timer_started_at is None and not session.paused
    later = opened.opened_at + timedelta(minutes=3)
    assert elapsed(session, later) == 0
    assert not round_due(session, later + timedelta(hours=1))
    with db.write() as s:
        assert show_round(s, sid, 0, now=later).shown_at == later
    with db.write() as s:  # shown again (a reload): the first showing counts
        assert show_round(s, sid, 0, now=later + timedelta(seconds=50)).shown_at == later
    with db.read() as s:
        session = get_session(s, sid)
    assert elapsed(session, later + timedelta(seconds=30)) == 30
    assert not round_due(session, later + timedelta(seconds=99))
    assert round_due(session, later + timedelta(seconds=100))


def test_a_round_paused_before_it_is_shown_starts_on_resume(db, open_session):
    sid = open_session(round_seconds=100)
    with db.write() as s:
        pause(s, sid, now=at(0))
    with db.write() as s:
        show_round(s, sid, 0, now=at(10))
    with db.read() as s:
        session = get_session(s, sid)
    assert elapsed(session, at(500)) == 0
    with db.write() as s:
        resume(s, sid, now=at(600))
    with db.read() as s:
        session = get_session(s, sid)
    assert elapsed(session, at(620)) == 20


def test_only_the_open_round_can_be_shown(db, open_session):
    sid = open_session()
    with pytest.raises(ConflictError, match="round 1 is not open yet; the open round is 0"):
        with db.write() as s:
            show_round(s, sid, 1)
    with db.write() as s:
        close_open_round(s, sid)
    with pytest.raises(ConflictError, match="training"), db.write() as s:
        show_round(s, sid, 0)


def test_no_time_limit_when_the_budget_is_zero(db, open_session):
    sid = open_session(round_seconds=0)
    with db.read() as s:
        session = get_session(s, sid)
    assert not round_due(session, datetime.now(UTC) + timedelta(days=3))


def test_pause_needs_an_open_round(db):
    with db.write() as s:
        sid = create_session(s, "GridWorld", "groupwise", SessionSettings()).id
    with pytest.raises(ConflictError, match="preparing"), db.write() as s:
        pause(s, sid)
