"""A session shared with annotators (docs/teams.md), on real SQLite and PostgreSQL: their
tokens, their judgements and undos, leased suggestions and pairs, the suggestions asked
twice, the team's counters and agreement, the export, and an old database's upgrade."""

import sqlite3
from datetime import timedelta

import pytest
from sqlalchemy import text

from groupwise.storage import (
    ConflictError,
    Database,
    ForbiddenError,
    InvalidError,
    NotFoundError,
)
from groupwise.storage import annotators as team_repo
from groupwise.storage import rounds as repo
from groupwise.storage.database import sqlite_url
from groupwise.storage.export import export_session, import_session
from groupwise.storage.export_jsonl import from_jsonl, to_jsonl
from groupwise.storage.export_parquet import from_parquet, to_parquet
from groupwise.storage.judgements import list_judgements
from groupwise.storage.judging import JudgementInput, add_judgement, undo_judgement
from groupwise.storage.models import utcnow
from groupwise.storage.sessions import get_round, get_session
from groupwise.storage.team import team_stats


def judgement(client_id, left, right, label="left", who="owner", source="explored"):
    return JudgementInput(client_id, 0, tuple(left), tuple(right), label, source,
                          annotator_id=who)  # fmt: skip


def test_annotators_get_a_token_of_their_own_and_lose_it_when_removed(db, open_session):
    sid = open_session()
    with db.write() as s:
        ada = team_repo.add_annotator(s, sid, "  Ada ")
        bob = team_repo.add_annotator(s, sid, "Bob")
    assert ada.name == "Ada" and ada.token != bob.token and ada.id.startswith("a-")
    with db.read() as s:
        assert team_repo.by_token(s, ada.token) == team_repo.Caller(ada.id, "Ada", sid)
        assert team_repo.by_token(s, "not-a-token") is None
        assert [a.name for a in team_repo.list_annotators(s, sid)] == ["Ada", "Bob"]
    with db.write() as s:
        team_repo.remove_annotator(s, sid, ada.id)
    with db.read() as s:
        assert team_repo.by_token(s, ada.token) is None
        assert [a.name for a in team_repo.list_annotators(s, sid)] == ["Bob"]
        assert team_repo.display_names(s, get_session(s, sid))[ada.id] == "Ada"
    with pytest.raises(NotFoundError, match="no annotator"), db.write() as s:
        team_repo.remove_annotator(s, sid, ada.id)
    with db.write() as s:  # a removed annotator's name is free again
        team_repo.add_annotator(s, sid, "Ada")


@pytest.mark.parametrize(
    ("name", "error", "message"),
    [
        ("", InvalidError, "must not be empty"),
        ("   ", InvalidError, "must not be empty"),
        ("x" * 101, InvalidError, "at most 100 characters"),
        ("Ada\nBob", InvalidError, "control character U\\+000A"),
        ("Ada\u200b", InvalidError, "control character U\\+200B"),
        ("owner", ConflictError, "already has an annotator named 'owner'"),
        ("bob", ConflictError, "already has an annotator named 'bob'"),
    ],
)
def test_annotator_names_are_checked(db, open_session, name, error, message):
    sid = open_session()
    with db.write() as s:
        team_repo.add_annotator(s, sid, "Bob")
    with pytest.raises(error, match=message), db.write() as s:
        team_repo.add_annotator(s, sid, name)


def test_only_the_annotator_who_made_a_judgement_can_undo_it(db, open_session):
    sid = open_session()
    with db.write() as s:
        ada = team_repo.add_annotator(s, sid, "Ada")
        mine = add_judgement(s, sid, judgement("1", ["b1"], ["b2"], who=ada.id))[0]
        owners = add_judgement(s, sid, judgement("2", ["b3"], ["b4"]))[0]
    assert (mine.annotator_id, owners.annotator_id) == (ada.id, "owner")
    refusal = f"judgement {mine.id} was made by Ada; only they can undo it"
    with pytest.raises(ForbiddenError, match=refusal), db.write() as s:
        undo_judgement(s, sid, mine.id)  # the owner
    with pytest.raises(ForbiddenError, match=f"{owners.id} was made by owner"), db.write() as s:
        undo_judgement(s, sid, owners.id, annotator_id=ada.id)
    with db.write() as s:
        assert undo_judgement(s, sid, mine.id, annotator_id=ada.id).undone
    # a retry under someone else's client id is another comparison
    with pytest.raises(ConflictError, match="already used"), db.write() as s:
        add_judgement(s, sid, judgement("2", ["b3"], ["b4"], who=ada.id))


def test_a_leased_suggestion_is_offered_to_nobody_else_until_the_lease_ends(db, open_session):
    sid = open_session()
    now = utcnow()
    with db.write() as s:
        rid = get_round(s, sid, 0).id
        ada = repo.next_suggestion(s, rid, holder="a-ada", lease_s=60, now=now)
        bob = repo.next_suggestion(s, rid, holder="a-bob", lease_s=60, now=now)
        again = repo.next_suggestion(s, rid, holder="a-ada", lease_s=60, now=now)
        eve = repo.next_suggestion(s, rid, holder="a-eve", lease_s=60, now=now)
        assert (ada.rank, bob.rank, again.rank, eve) == (0, 1, 0, None)
        later = now + timedelta(seconds=61)
        assert repo.next_suggestion(s, rid, holder="a-eve", lease_s=60, now=later).rank == 0
        # passing over a suggestion gives up its lease (Bob's has ended too)
        passed = [(["b0", "b1"], ["b2", "b3"])]
        assert repo.next_suggestion(s, rid, passed, holder="a-eve", lease_s=60, now=later).rank == 1
        assert repo.next_suggestion(s, rid, holder="a-ada", lease_s=60, now=later).rank == 0
        # without leases everyone gets the best one, as before sessions were shared
        assert repo.next_suggestion(s, rid, holder="a-zed").rank == 0


def test_a_leased_pair_is_asked_of_nobody_else(db, open_session):
    sid = open_session("pairwise")
    now = utcnow()
    with db.write() as s:
        rid = get_round(s, sid, 0).id
        ada = repo.pairwise_next(s, rid, holder="a-ada", lease_s=60, now=now)
        bob = repo.pairwise_next(s, rid, holder="a-bob", lease_s=60, now=now)
    assert [(p.a, p.b) for p in ada] == [("b0", "b1"), ("b2", "b3")]
    assert [(p.a, p.b) for p in bob] == [("b2", "b3"), ("b4", "b5")]


def test_a_chosen_suggestion_waits_for_a_second_annotators_answer(db, open_session):
    sid = open_session(overlap_share=1.0)
    with db.write() as s:
        rid = get_round(s, sid, 0).id
        ada = team_repo.add_annotator(s, sid, "Ada")
        bob = team_repo.add_annotator(s, sid, "Bob")
        first = add_judgement(s, sid, judgement("1", ["b0", "b1"], ["b2", "b3"], who=ada.id))[0]
        assert first.suggestion_id is not None
        # not asked of Ada again, but of Bob, until he answers it
        assert repo.next_suggestion(s, rid, holder=ada.id).rank == 1
        assert repo.next_suggestion(s, rid, holder=bob.id).rank == 0
        second = add_judgement(
            s, sid, judgement("2", ["b2", "b3"], ["b0", "b1"], "right", who=bob.id)
        )[0]
        assert second.suggestion_id == first.suggestion_id
        assert repo.next_suggestion(s, rid, holder=bob.id).rank == 1
    with db.read() as s:
        ada_stats = next(t for t in team_stats(s, get_session(s, sid)) if t.id == ada.id)
    assert (ada_stats.agreement.n, ada_stats.agreement.share) == (4, 1.0)


def test_alone_nothing_is_asked_twice(db, open_session):
    sid = open_session(overlap_share=1.0)
    with db.write() as s:
        rid = get_round(s, sid, 0).id
        add_judgement(s, sid, judgement("1", ["b0", "b1"], ["b2", "b3"]))
        assert repo.next_suggestion(s, rid).rank == 1
        assert repo.next_suggestion(s, rid, holder="a-someone").rank == 1


def test_the_team_counts_and_agreement(db, open_session):
    sid = open_session()
    t0 = utcnow()
    with db.write() as s:
        ada = team_repo.add_annotator(s, sid, "Ada")
        bob = team_repo.add_annotator(s, sid, "Bob")
        team_repo.record_view(s, sid, 0, team_repo.Caller(ada.id, "Ada", sid), t0)
        team_repo.record_view(s, sid, 0, team_repo.Caller(ada.id, "Ada", sid), t0 + timedelta(9))
        team_repo.record_view(s, sid, 0, team_repo.OWNER_CALLER, t0 + timedelta(seconds=30))
        # one pair each: Ada and Bob agree on b1 vs b2 (in either order), not on b3 vs b4
        add_judgement(s, sid, judgement("1", ["b1"], ["b2"], "left", who=ada.id))
        add_judgement(s, sid, judgement("2", ["b2"], ["b1"], "right", who=bob.id))
        add_judgement(s, sid, judgement("3", ["b3"], ["b4"], "left", who=ada.id))
        add_judgement(s, sid, judgement("4", ["b3"], ["b4"], "equal", who=bob.id))
        add_judgement(s, sid, judgement("5", ["b5", "b6"], ["b7"], "left"))
    now = t0 + timedelta(seconds=100)
    with db.read() as s:
        stats = {t.id: t for t in team_stats(s, get_session(s, sid), now)}
    assert list(stats) == ["owner", ada.id, bob.id]
    assert [(t.name, t.comparisons, t.pairs) for t in stats.values()] == [
        ("owner", 1, 2), ("Ada", 2, 2), ("Bob", 2, 2)
    ]  # fmt: skip
    assert stats[ada.id].shown_s == pytest.approx(100.0)
    assert stats["owner"].shown_s == pytest.approx(70.0)
    assert stats[bob.id].shown_s == 0.0
    # Ada: (1, 1) alike, (1, ½) not: p_o = ½, p_e = 1·½ = ½ → κ = 0
    assert stats[ada.id].agreement.n == 2 and stats[ada.id].agreement.share == 0.5
    assert stats[ada.id].agreement.kappa == pytest.approx(0.0)
    assert stats["owner"].agreement.n == 0 and stats["owner"].agreement.kappa is None
    assert stats["owner"].model_agreement.n == 0  # no reward model's predictions given


def test_the_model_agreement_uses_the_rounds_predictions_after_round_zero(db, open_session):
    sid = open_session()
    with db.write() as s:
        add_judgement(s, sid, judgement("1", ["b1"], ["b2"], "left"))
        session = get_session(s, sid)
        session.round = 1  # as if the judgement were one of round 1
        s.execute(text("UPDATE judgements SET round_index = 1"))
    scores = {"b1": 2.0, "b2": 1.0}
    with db.read() as s:
        owner = team_stats(s, get_session(s, sid), scores=lambda sid, r, pool: scores)[0]
    assert (owner.model_agreement.share, owner.model_agreement.n) == (1.0, 1)


def test_the_export_names_who_made_each_judgement_and_the_import_keeps_it(db, open_session):
    sid = open_session()
    with db.write() as s:
        ada = team_repo.add_annotator(s, sid, "Ada")
        add_judgement(s, sid, judgement("1", ["b1"], ["b2"], who=ada.id))
        add_judgement(s, sid, judgement("2", ["b1"], ["b2"]))
        team_repo.remove_annotator(s, sid, ada.id)
    with db.read() as s:
        export = export_session(s, sid)
    assert [(j.annotator, j.annotator_id) for j in export.judgements] == [
        ("Ada", ada.id), ("owner", "owner")
    ]  # fmt: skip
    assert [(a.id, a.name, a.comparisons, a.removed) for a in export.annotators] == [
        ("owner", "owner", 1, False), (ada.id, "Ada", 1, True)
    ]  # fmt: skip
    assert export.annotators[1].agreement.n == 1
    for again in (from_jsonl(to_jsonl(export)), from_parquet(to_parquet(export))):
        assert again.judgements == export.judgements
        assert again.annotators == export.annotators
    with db.write() as s:
        copy = import_session(s, export).id
    with db.read() as s:
        copied = list_judgements(s, copy)
        names = team_repo.display_names(s, get_session(s, copy))
        assert team_repo.list_annotators(s, copy) == []  # none can act: no tokens
    assert copied[0].annotator_id not in ("owner", ada.id)
    assert names[copied[0].annotator_id] == "Ada" and copied[1].annotator_id == "owner"


@pytest.mark.parametrize(("write", "read"), [(to_jsonl, from_jsonl), (to_parquet, from_parquet)])
def test_an_import_keeps_everyones_time_shown(db, open_session, write, read):
    sid = open_session()
    t0 = utcnow()
    with db.write() as s:
        ada = team_repo.add_annotator(s, sid, "Ada")
        team_repo.record_view(s, sid, 0, team_repo.Caller(ada.id, "Ada", sid), t0)
        team_repo.record_view(s, sid, 0, team_repo.OWNER_CALLER, t0 + timedelta(seconds=10))
        add_judgement(s, sid, judgement("1", ["b1"], ["b2"], who=ada.id))
        get_round(s, sid, 0).closed_at = t0 + timedelta(seconds=48.8)
    with db.read() as s:
        export = export_session(s, sid)
    with db.write() as s:
        copy = import_session(s, read(write(export))).id
    with db.read() as s:
        before = {t.name: t.shown_s for t in team_stats(s, get_session(s, sid))}
        imported = team_stats(s, get_session(s, copy), include_removed=True)
        after = {t.name: t.shown_s for t in imported}
    # issue 40: Ada's 48.8 s came back as 0.0 while the owner's stayed
    assert before == after == {"owner": pytest.approx(38.8), "Ada": pytest.approx(48.8)}


def test_an_older_database_keeps_working_and_its_judgements_are_the_owners(tmp_path):
    path = tmp_path / "old.db"
    first = Database(sqlite_url(path))
    first.create_schema()
    first.dispose()
    with sqlite3.connect(path) as old:  # the tables as the version before annotators
        for table, column in [
            ("judgements", "annotator_id"),
            ("judgements", "suggestion_id"),
            ("suggestions", "leased_to"),
            ("suggestions", "lease_until"),
            ("suggestions", "first_by"),
            ("pairwise_queue", "leased_to"),
            ("pairwise_queue", "lease_until"),
        ]:
            old.execute(f'ALTER TABLE "{table}" DROP COLUMN "{column}"')
        old.execute("DROP TABLE annotators")
        old.execute("DROP TABLE round_views")
        old.execute(
            "INSERT INTO sessions (id, env, mode, settings, annotator, phase, round, "
            "progress_phase, progress_fraction, progress_message, timer_elapsed_s, paused, "
            "judgement_seq, revision, created_at, updated_at) VALUES ('s-old', 'GridWorld', "
            "'groupwise', '{}', 'Ann', 'finished', 0, '', 1, '', 0, 0, 1, 1, "
            "'2030-01-01 00:00:00', '2030-01-01 00:00:00')"
        )
        old.execute(
            "INSERT INTO rounds (id, session_id, \"index\", phase) VALUES (1, 's-old', 0, 'closed')"
        )
        old.execute(
            "INSERT INTO judgements (id, session_id, round_id, round_index, seq, client_id, "
            "left, right, label, source, seconds, edits, annotator, created_at, undone, "
            "revision) VALUES (1, 's-old', 1, 0, 0, 'c', '[\"b1\"]', '[\"b2\"]', 'left', "
            "'explored', 0, 0, '', '2030-01-01 00:00:00', 0, 1)"
        )
    database = Database(sqlite_url(path))
    try:
        database.create_schema()
        with database.read() as s:
            [stored] = list_judgements(s, "s-old")
            owner = team_stats(s, get_session(s, "s-old"))[0]
            assert team_repo.list_annotators(s, "s-old") == []
        assert stored.annotator_id == "owner" and stored.suggestion_id is None
        assert (owner.id, owner.name, owner.comparisons) == ("owner", "Ann", 1)
    finally:
        database.dispose()
