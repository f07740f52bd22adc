"""The database schema: SQLAlchemy 2 declarative models (SQLite by default, PostgreSQL too).

Only portable column types are used (JSON via `sqlalchemy.JSON`, times as timezone-aware
UTC through `UTCDateTime`); no SQLite-only SQL. Row classes end in `Row` so they are never
mistaken for the frozen records the repositories hand across module lines.

Tables (one session owns everything below it; deleting a session cascades):

    sessions          one RLHF session: env, mode, settings, phase, progress, timer
    rounds            round r of a session: its pool directory, open / close times (or,
                      for a round without feedback, its PPO steps on the frozen reward)
    behaviours        the pool of a round: "b<i>", clip and poster ids, true return
    judgements        the record of truth of one comparison (SPEC §6)
    pairs             the preference pairs derived from a judgement (deleted with it)
    checkpoints       the checkpoint directory written after a round's training
    suggestions       the round's ranked group suggestions (SPEC §5), used or not
    suggestion_edges  the round's top-k pairwise suggestion edges for the view
    pairwise_queue    the round's pairs for the pairwise baseline, best first
    training_points   the agent's learning as it happens: PPO steps, true return, last refit
    annotators        the people a session's owner shares it with: name, token hash
    round_views       when each annotator first showed a round (their time shown)

Who made a judgement is `judgements.annotator_id` (null: the session's owner, as every
judgement stored before sessions could be shared); docs/teams.md.
"""

from datetime import UTC, datetime
from typing import Any, ClassVar

from sqlalchemy import (
    JSON,
    DateTime,
    Dialect,
    Float,
    ForeignKey,
    Index,
    Integer,
    String,
    Text,
    TypeDecorator,
    UniqueConstraint,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship


class UTCDateTime(TypeDecorator[datetime]):
    """A timezone-aware UTC datetime on every backend (SQLite drops the zone: we restore it)."""

    impl = DateTime(timezone=True)
    cache_ok = True

    def process_bind_param(self, value: datetime | None, dialect: Dialect) -> datetime | None:
        if value is None:
            return None
        if value.tzinfo is None:
            raise ValueError("naive datetimes are not stored; use datetime.now(UTC)")
        return value.astimezone(UTC)

    def process_result_value(self, value: datetime | None, dialect: Dialect) -> datetime | None:
        if value is None:
            return None
        return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


MAX_INTEGER = 2**31 - 1
"""The largest id, revision or count an ``Integer`` column holds on every backend
(PostgreSQL's ``integer``; SQLite's are 64-bit): a larger one in a query matches no row, and
on PostgreSQL it fails the query, so the repositories answer it before they ask."""


def utcnow() -> datetime:
    """The current time, timezone-aware UTC (the only kind of time stored)."""
    return datetime.now(UTC)


class Base(DeclarativeBase):
    type_annotation_map: ClassVar[dict[Any, Any]] = {
        dict[str, Any]: JSON,
        list[str]: JSON,
        datetime: UTCDateTime,
    }


class SessionRow(Base):
    """One RLHF session. `phase` is the lifecycle of docs/app.md; `round` the current round."""

    __tablename__ = "sessions"

    id: Mapped[str] = mapped_column(String(32), primary_key=True)
    env: Mapped[str] = mapped_column(String(200))
    mode: Mapped[str] = mapped_column(String(16))
    settings: Mapped[dict[str, Any]]
    annotator: Mapped[str] = mapped_column(String(200), default="")
    phase: Mapped[str] = mapped_column(String(16), index=True)
    round: Mapped[int] = mapped_column(Integer, default=0)
    failed_phase: Mapped[str | None] = mapped_column(String(16), default=None)
    """The phase that failed (`preparing` or `training`): what `retry` re-queues."""
    error: Mapped[str | None] = mapped_column(Text, default=None)
    progress_phase: Mapped[str] = mapped_column(String(32), default="")
    progress_fraction: Mapped[float] = mapped_column(Float, default=0.0)
    progress_message: Mapped[str] = mapped_column(Text, default="")
    timer_elapsed_s: Mapped[float] = mapped_column(Float, default=0.0)
    """Seconds the open round's timer ran before its current run (see `timer_started_at`)."""
    timer_started_at: Mapped[datetime | None] = mapped_column(default=None)
    """When the timer's current run started; None while it is stopped (paused, no round
    open, or the open round not shown in a page yet)."""
    paused: Mapped[bool] = mapped_column(default=False)
    judgement_seq: Mapped[int] = mapped_column(Integer, default=0)
    """Judgements numbered so far (the next gets this number): seeds their pair derivation."""
    revision: Mapped[int] = mapped_column(Integer, default=0)
    """Bumped by every change a page should hear of (the event stream polls it)."""
    origin: Mapped[str | None] = mapped_column(String(200), default=None)
    """For an imported session, the id of the session it was exported from."""
    created_at: Mapped[datetime] = mapped_column(default=utcnow)
    updated_at: Mapped[datetime] = mapped_column(default=utcnow)

    rounds: Mapped[list["RoundRow"]] = relationship(
        back_populates="session", cascade="all, delete-orphan", passive_deletes=True
    )


class RoundRow(Base):
    """Round `index` of a session. `phase`: preparing → open → closed."""

    __tablename__ = "rounds"
    __table_args__ = (UniqueConstraint("session_id", "index"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id", ondelete="CASCADE"))
    index: Mapped[int] = mapped_column(Integer)
    phase: Mapped[str] = mapped_column(String(16))
    pool_dir: Mapped[str | None] = mapped_column(Text, default=None)
    opened_at: Mapped[datetime | None] = mapped_column(default=None)
    """When the worker opened the round (its pool is ready)."""
    shown_at: Mapped[datetime | None] = mapped_column(default=None)
    """When a page first showed the open round; its timer runs from then (docs/app.md)."""
    closed_at: Mapped[datetime | None] = mapped_column(default=None)
    close_reason: Mapped[str | None] = mapped_column(String(32), default=None)
    """Why the round ended: "user", "comparisons", "time" (or "imported")."""
    stats: Mapped[dict[str, Any] | None] = mapped_column(JSON, default=None)
    """What the training after this round reported (reward fit, PPO, true return)."""
    frozen_steps: Mapped[int | None] = mapped_column(Integer, default=None)
    """PPO env steps of a round without feedback, on the frozen learned reward (the final
    phase, or "Continue training"); null for a feedback round. Such a round has no pool."""

    session: Mapped[SessionRow] = relationship(back_populates="rounds")


class BehaviourRow(Base):
    """Behaviour `name` ("b<i>", the tree's leaf id) of a round's pool."""

    __tablename__ = "behaviours"
    __table_args__ = (UniqueConstraint("round_id", "name"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    round_id: Mapped[int] = mapped_column(ForeignKey("rounds.id", ondelete="CASCADE"), index=True)
    name: Mapped[str] = mapped_column(String(16))
    index: Mapped[int] = mapped_column(Integer)
    clip: Mapped[str] = mapped_column(String(80))
    poster: Mapped[str] = mapped_column(String(80))
    true_return: Mapped[float | None] = mapped_column(Float, default=None)
    """For evaluation and label error rates only: never sent to the page."""


class JudgementRow(Base):
    """One comparison as the user gave it: the record of truth (SPEC §6).

    `left` / `right` are lists of behaviour names of round `round_index`; `label` is
    "left", "right" or "equal". An undone judgement keeps its row (`undone`) and loses its
    pairs.
    """

    __tablename__ = "judgements"
    __table_args__ = (
        UniqueConstraint("session_id", "client_id"),
        UniqueConstraint("session_id", "seq"),
        Index("ix_judgements_session_revision", "session_id", "revision"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id", ondelete="CASCADE"))
    round_id: Mapped[int] = mapped_column(ForeignKey("rounds.id", ondelete="CASCADE"), index=True)
    round_index: Mapped[int] = mapped_column(Integer)
    seq: Mapped[int] = mapped_column(Integer)
    client_id: Mapped[str] = mapped_column(String(100))
    left: Mapped[list[str]]
    right: Mapped[list[str]]
    label: Mapped[str] = mapped_column(String(8))
    source: Mapped[str] = mapped_column(String(16))
    seconds: Mapped[float] = mapped_column(Float, default=0.0)
    edits: Mapped[int] = mapped_column(Integer, default=0)
    annotator: Mapped[str] = mapped_column(String(200), default="")
    """The name it was given under when stored (the owner's free text, or the annotator's
    name)."""
    annotator_id: Mapped[str | None] = mapped_column(String(32), default=None)
    """The annotator who made it (`AnnotatorRow.id`); null: the session's owner."""
    suggestion_id: Mapped[int | None] = mapped_column(Integer, default=None)
    """The group suggestion it answered (`SuggestionRow.id`), if any."""
    created_at: Mapped[datetime] = mapped_column(default=utcnow)
    undone: Mapped[bool] = mapped_column(default=False)
    undone_at: Mapped[datetime | None] = mapped_column(default=None)
    revision: Mapped[int] = mapped_column(Integer, default=0)
    """The session revision of this row's last change (insert or undo)."""

    pairs: Mapped[list["PairRow"]] = relationship(
        back_populates="judgement",
        cascade="all, delete-orphan",
        passive_deletes=True,
        order_by="PairRow.position",
    )


class PairRow(Base):
    """A preference pair derived from a judgement: behaviour names and P(a preferred)."""

    __tablename__ = "pairs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    judgement_id: Mapped[int] = mapped_column(
        ForeignKey("judgements.id", ondelete="CASCADE"), index=True
    )
    position: Mapped[int] = mapped_column(Integer)
    a: Mapped[str] = mapped_column(String(16))
    b: Mapped[str] = mapped_column(String(16))
    label: Mapped[float] = mapped_column(Float)

    judgement: Mapped[JudgementRow] = relationship(back_populates="pairs")


class CheckpointRow(Base):
    """The checkpoint directory written after round `round_id`'s training."""

    __tablename__ = "checkpoints"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    round_id: Mapped[int] = mapped_column(ForeignKey("rounds.id", ondelete="CASCADE"), index=True)
    path: Mapped[str] = mapped_column(Text)
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


class SuggestionRow(Base):
    """A suggested group comparison (SPEC §5), `rank` 0 best; `used` once it was answered."""

    __tablename__ = "suggestions"
    __table_args__ = (
        UniqueConstraint("round_id", "rank"),
        Index("ix_suggestions_round_key", "round_id", "key"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    round_id: Mapped[int] = mapped_column(ForeignKey("rounds.id", ondelete="CASCADE"))
    rank: Mapped[int] = mapped_column(Integer)
    left: Mapped[list[str]]
    right: Mapped[list[str]]
    key: Mapped[str] = mapped_column(String(1024))
    """The two groups as one string, equal for equal groups in either order (`query_key`)."""
    left_node: Mapped[str] = mapped_column(String(64))
    right_node: Mapped[str] = mapped_column(String(64))
    score: Mapped[float] = mapped_column(Float)
    used: Mapped[bool] = mapped_column(default=False)
    leased_to: Mapped[str | None] = mapped_column(String(32), default=None)
    """Who it is offered to now ("owner" or an annotator id) until `lease_until`."""
    lease_until: Mapped[datetime | None] = mapped_column(default=None)
    first_by: Mapped[str | None] = mapped_column(String(32), default=None)
    """Set when its first answer chose it for a second annotator's (agreement): who gave
    that first answer; it stays unused until someone else answers it."""


class SuggestionEdgeRow(Base):
    """A top-k pairwise suggestion edge of the exploration view, score in (0, 1]."""

    __tablename__ = "suggestion_edges"
    __table_args__ = (UniqueConstraint("round_id", "rank"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    round_id: Mapped[int] = mapped_column(ForeignKey("rounds.id", ondelete="CASCADE"))
    rank: Mapped[int] = mapped_column(Integer)
    a: Mapped[str] = mapped_column(String(16))
    b: Mapped[str] = mapped_column(String(16))
    score: Mapped[float] = mapped_column(Float)


class PairQueueRow(Base):
    """The pairwise baseline's queue of a round, `position` 0 first (SPEC §5, §9)."""

    __tablename__ = "pairwise_queue"
    __table_args__ = (UniqueConstraint("round_id", "position"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    round_id: Mapped[int] = mapped_column(ForeignKey("rounds.id", ondelete="CASCADE"))
    position: Mapped[int] = mapped_column(Integer)
    a: Mapped[str] = mapped_column(String(16))
    b: Mapped[str] = mapped_column(String(16))
    score: Mapped[float] = mapped_column(Float)
    skipped: Mapped[bool] = mapped_column(default=False)
    leased_to: Mapped[str | None] = mapped_column(String(32), default=None)
    """Who it is asked of now ("owner" or an annotator id) until `lease_until`."""
    lease_until: Mapped[datetime | None] = mapped_column(default=None)


class TrainingPointRow(Base):
    """One point of a session's learning curve (`groupwise.storage.training`): the worker
    writes one after each refit and evaluation of a continuous round, and one per trained
    round."""

    __tablename__ = "training_points"
    __table_args__ = (Index("ix_training_points_session_revision", "session_id", "revision"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id", ondelete="CASCADE"))
    round: Mapped[int] = mapped_column(Integer)
    at: Mapped[datetime] = mapped_column(default=utcnow)
    ppo_steps: Mapped[int] = mapped_column(Integer)
    """The agent's PPO env steps so far."""
    true_return: Mapped[float | None] = mapped_column(Float, default=None)
    """The greedy policy's mean true return now; null when the point is a refit only."""
    pairs: Mapped[int] = mapped_column(Integer)
    """Preference pairs the reward model was last fitted on (all rounds)."""
    reward_val_accuracy: Mapped[float | None] = mapped_column(Float, default=None)
    """The last fit's held-out accuracy; null without a validation split."""
    pool_steps: Mapped[int] = mapped_column(Integer)
    """PPO env steps of the policy that sampled round `round`'s pool."""
    revision: Mapped[int] = mapped_column(Integer, default=0)
    """The session revision the point was written at (the event stream's cursor)."""


class AnnotatorRow(Base):
    """A person the session's owner shares the session with (docs/teams.md). Only the
    SHA-256 of their token is kept; a removed annotator keeps the row (their judgements
    stay theirs) and loses the token."""

    __tablename__ = "annotators"
    __table_args__ = (Index("ix_annotators_session", "session_id"),)

    id: Mapped[str] = mapped_column(String(32), primary_key=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id", ondelete="CASCADE"))
    name: Mapped[str] = mapped_column(String(200))
    token_sha256: Mapped[str | None] = mapped_column(String(64), unique=True, default=None)
    """Hex SHA-256 of the annotator's token; null once removed (or imported)."""
    created_at: Mapped[datetime] = mapped_column(default=utcnow)
    removed_at: Mapped[datetime | None] = mapped_column(default=None)


class RoundViewRow(Base):
    """When an annotator ("owner" or an annotator id) first showed a round in a page."""

    __tablename__ = "round_views"
    __table_args__ = (UniqueConstraint("round_id", "annotator"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    round_id: Mapped[int] = mapped_column(ForeignKey("rounds.id", ondelete="CASCADE"))
    annotator: Mapped[str] = mapped_column(String(32))
    shown_at: Mapped[datetime] = mapped_column()
