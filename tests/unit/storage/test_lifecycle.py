"""A session's phase changes after the round: training, the next round, failure and retry."""

import pytest

from groupwise.storage import ConflictError, SessionSettings
from groupwise.storage.lifecycle import close_open_round, finish_training, mark_failed, retry
from groupwise.storage.phases import PREPARING, ROUND_PREPARING
from groupwise.storage.sessions import create_session, get_round, get_session


def test_training_moves_on_to_the_next_round_then_finishes(db, open_session):
    sid = open_session(rounds=2)
    with db.write() as s:
        close_open_round(s, sid)
    with db.write() as s:
        assert finish_training(s, sid, 0, "sessions/x/checkpoints/round-0000", {"a": 1})
    with db.read() as s:
        session = get_session(s, sid)
        assert (session.phase, session.round) == (PREPARING, 1)
        assert get_round(s, sid, 0).stats == {"a": 1}
        assert get_round(s, sid, 1).phase == ROUND_PREPARING
    with db.write() as s:  # a late report for a round that moved on changes nothing
        assert not finish_training(s, sid, 0, "x", {})


def test_failure_and_retry(db):
    with db.write() as s:
        sid = create_session(s, "GridWorld", "groupwise", SessionSettings()).id
    with pytest.raises(ConflictError, match="has not failed"), db.write() as s:
        retry(s, sid)
    with db.write() as s:
        assert mark_failed(s, sid, PREPARING, "boom") is not None
    with db.read() as s:
        failed = get_session(s, sid)
    assert (failed.phase, failed.failed_phase, failed.error) == ("failed", "preparing", "boom")
    with db.write() as s:
        retry(s, sid)
    with db.read() as s:
        again = get_session(s, sid)
    assert (again.phase, again.error, again.progress_phase) == ("preparing", None, "queued")
