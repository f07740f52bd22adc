"""Suggestions and the pairwise queue of a prepared round, on a real SQLite file."""

import pytest

from groupwise.storage import NotFoundError
from groupwise.storage import rounds as repo
from groupwise.storage.judging import JudgementInput, add_judgement, undo_judgement
from groupwise.storage.sessions import get_round


def _round_id(db, sid: str) -> int:
    with db.read() as s:
        return get_round(s, sid, 0).id


def test_next_suggestion_skips_excluded_and_answered_ones(db, open_session):
    sid = open_session()
    rid = _round_id(db, sid)
    with db.read() as s:
        first = repo.next_suggestion(s, rid)
        assert (first.left, first.right) == (["b0", "b1"], ["b2", "b3"])
        # excluded in either side order
        assert repo.next_suggestion(s, rid, [(["b3", "b2"], ["b1", "b0"])]).rank == 1
    with db.write() as s:  # answering it exactly (sides swapped) uses it up
        add_judgement(
            s, sid, JudgementInput("1", 0, ("b2", "b3"), ("b0", "b1"), "left", "explored")
        )
    with db.read() as s:
        assert repo.next_suggestion(s, rid).rank == 1
    with db.write() as s:  # an edited suggestion uses up the one it overlaps most
        add_judgement(s, sid, JudgementInput("2", 0, ("b4",), ("b6",), "right", "suggested"))
    with db.read() as s:
        assert repo.next_suggestion(s, rid) is None


def test_pairwise_queue_skips_judged_and_skipped_pairs(db, open_session):
    sid = open_session(mode="pairwise")
    rid = _round_id(db, sid)
    with db.read() as s:
        assert [(e.a, e.b) for e in repo.pairwise_next(s, rid)] == [("b0", "b1"), ("b2", "b3")]
    with db.write() as s:
        judged, _ = add_judgement(
            s, sid, JudgementInput("1", 0, ("b1",), ("b0",), "left", "pairwise")
        )
    with db.read() as s:
        assert [(e.a, e.b) for e in repo.pairwise_next(s, rid)] == [("b2", "b3"), ("b4", "b5")]
    with db.write() as s:
        repo.skip_pair(s, rid, "b3", "b2")
    with db.read() as s:
        assert [(e.a, e.b) for e in repo.pairwise_next(s, rid)] == [("b4", "b5")]
    with db.write() as s:  # an undone answer puts its pair back
        undo_judgement(s, sid, judged.id)
    with db.read() as s:
        assert [(e.a, e.b) for e in repo.pairwise_next(s, rid)] == [("b0", "b1"), ("b4", "b5")]
    with pytest.raises(NotFoundError), db.write() as s:
        repo.skip_pair(s, rid, "b0", "b9")


def test_compared_lists_behaviours_of_live_judgements(db, open_session):
    sid = open_session()
    with db.write() as s:
        add_judgement(s, sid, JudgementInput("1", 0, ("b5", "b1"), ("b2",), "left", "explored"))
        gone, _ = add_judgement(
            s, sid, JudgementInput("2", 0, ("b7",), ("b8",), "left", "explored")
        )
        undo_judgement(s, sid, gone.id)
    with db.read() as s:
        assert repo.compared(s, get_round(s, sid, 0)) == ["b5", "b1", "b2"]
