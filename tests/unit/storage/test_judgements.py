"""Reading judgements back (`storage.judgements`) on real SQLite and PostgreSQL databases;
storing them is `test_judging.py`."""

import pytest

from groupwise.storage import NotFoundError
from groupwise.storage.judgements import list_judgements
from groupwise.storage.judging import JudgementInput, add_judgement, undo_judgement
from groupwise.storage.training import list_points


def test_ids_and_revisions_beyond_an_integer_column_match_nothing(db, open_session):
    # PostgreSQL's integer is 32-bit: such a number failed the query there (a 500)
    sid = open_session()
    with db.write() as s:
        judgement = JudgementInput("c1", 0, ("b1", "b7"), ("b3",), "left", "explored")
        record, _ = add_judgement(s, sid, judgement)
    with pytest.raises(NotFoundError, match="no judgement 4611686018427387904"), db.write() as s:
        undo_judgement(s, sid, 2**62)
    with db.read() as s:
        assert list_judgements(s, sid, after_revision=2**62) == []
        assert list_judgements(s, sid, after_revision=0) == [record]
        assert list_points(s, sid, after_revision=2**62) == []
