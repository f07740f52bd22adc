"""The people a session is shared with (docs/teams.md): the owner and the annotators.

The **owner** holds the server's token (or, on a loopback server without one, is whoever
sends no token): every session is theirs, and only they add and remove annotators, end
rounds and change what the session does. An **annotator** is a name and a token of one
session: `add_annotator` makes the token, keeps only its SHA-256, and hands the token back
once. `by_token` finds the annotator of a token (None for a removed one: 401).

Everyone acting on a session is a `Caller`, keyed by `Caller.id` ("owner" or the
annotator's id): the key that judgements (`JudgementRow.annotator_id`, null for the owner),
suggestion leases and round views record.
"""

import hashlib
import secrets
import unicodedata
from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession

from groupwise.storage.errors import ConflictError, InvalidError, NotFoundError
from groupwise.storage.models import AnnotatorRow, RoundViewRow, SessionRow, utcnow
from groupwise.storage.sessions import get_round, get_session, touch

OWNER = "owner"
"""The owner's id wherever an annotator's id may stand."""
OWNER_NAME = "owner"
"""The owner's name when the session names none (`SessionRow.annotator`)."""
MAX_NAME = 100
"""Longest annotator name, in characters."""
_REFUSED_CATEGORIES = frozenset({"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"})
"""Unicode categories a name may not hold: control and format characters, surrogates,
private-use and unassigned code points, line and paragraph separators."""


@dataclass(frozen=True)
class Caller:
    """Who sends a request: the owner (`session_id` None: every session) or an annotator
    of one session."""

    id: str
    name: str
    session_id: str | None

    @property
    def is_owner(self) -> bool:
        return self.id == OWNER


OWNER_CALLER = Caller(OWNER, OWNER_NAME, None)
"""The owner, before their name in a session is known (`owner_name`)."""


@dataclass(frozen=True)
class NewAnnotator:
    """An annotator just added: their token, shown this once."""

    id: str
    name: str
    token: str


@dataclass(frozen=True)
class AnnotatorRecord:
    """An annotator of a session (`removed`: their token no longer works)."""

    id: str
    name: str
    created_at: datetime
    removed: bool


def token_digest(token: str) -> str:
    """The hex SHA-256 of a token, as stored."""
    return hashlib.sha256(token.encode()).hexdigest()


def owner_name(session: SessionRow) -> str:
    """The owner's name in a session: the session's annotator, else "owner"."""
    return session.annotator or OWNER_NAME


def check_name(name: str) -> str:
    """`name` without surrounding white space. Raises InvalidError, naming what is wrong:
    empty, longer than `MAX_NAME`, or holding a control or invisible character."""
    name = name.strip()
    if not name:
        raise InvalidError("an annotator's name must not be empty")
    if len(name) > MAX_NAME:
        raise InvalidError(f"an annotator's name may have at most {MAX_NAME} characters")
    for char in name:
        if unicodedata.category(char) in _REFUSED_CATEGORIES:
            raise InvalidError(
                f"an annotator's name may not hold the control character U+{ord(char):04X}"
            )
    return name


def add_annotator(
    s: DbSession, session_id: str, name: str, now: datetime | None = None
) -> NewAnnotator:
    """Add an annotator named `name` to the session, with a new token.

    Raises NotFoundError (unknown session), InvalidError (`check_name`), ConflictError (the
    name is the owner's or another present annotator's, compared without case).
    """
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    name = check_name(name)
    taken = {owner_name(session).casefold()} | {
        a.name.casefold() for a in list_annotators(s, session_id)
    }
    if name.casefold() in taken:
        raise ConflictError(f"session {session_id} already has an annotator named {name!r}")
    token = secrets.token_urlsafe(24)
    row = AnnotatorRow(
        id=f"a-{secrets.token_hex(6)}",
        session_id=session_id,
        name=name,
        token_sha256=token_digest(token),
        created_at=now,
    )
    s.add(row)
    touch(session, now)
    s.flush()
    return NewAnnotator(id=row.id, name=name, token=token)


def list_annotators(
    s: DbSession, session_id: str, *, include_removed: bool = False
) -> list[AnnotatorRecord]:
    """The session's annotators in the order they were added (not the owner)."""
    query = select(AnnotatorRow).where(AnnotatorRow.session_id == session_id)
    if not include_removed:
        query = query.where(AnnotatorRow.removed_at.is_(None))
    rows = s.scalars(query.order_by(AnnotatorRow.created_at, AnnotatorRow.id))
    return [AnnotatorRecord(r.id, r.name, r.created_at, r.removed_at is not None) for r in rows]


def remove_annotator(
    s: DbSession, session_id: str, annotator_id: str, now: datetime | None = None
) -> None:
    """Remove an annotator: their token stops working, their judgements stay theirs.

    Raises NotFoundError (unknown session, or no such present annotator in it).
    """
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    row = s.get(AnnotatorRow, annotator_id)
    if row is None or row.session_id != session_id or row.removed_at is not None:
        raise NotFoundError(f"session {session_id} has no annotator {annotator_id!r}")
    row.removed_at = now
    row.token_sha256 = None
    touch(session, now)


def by_token(s: DbSession, token: str) -> Caller | None:
    """The present annotator whose token `token` is, or None."""
    row = s.scalars(
        select(AnnotatorRow).where(
            AnnotatorRow.token_sha256 == token_digest(token), AnnotatorRow.removed_at.is_(None)
        )
    ).one_or_none()
    return None if row is None else Caller(row.id, row.name, row.session_id)


def display_names(s: DbSession, session: SessionRow) -> dict[str, str]:
    """Id → name of everyone in the session, the owner and removed annotators included."""
    found = {OWNER: owner_name(session)}
    for record in list_annotators(s, session.id, include_removed=True):
        found[record.id] = record.name
    return found


def maker_name(
    s: DbSession, session: SessionRow, annotator_id: str | None, stored: str = ""
) -> str:
    """The name of who made a judgement: an annotator's name, or for the owner's
    (`annotator_id` None or "owner") the name it was stored under, else the owner's."""
    if annotator_id is None or annotator_id == OWNER:
        return stored or owner_name(session)
    row = s.get(AnnotatorRow, annotator_id)
    return row.name if row is not None else stored or annotator_id


def record_view(
    s: DbSession, session_id: str, round_index: int, caller: Caller, now: datetime | None = None
) -> None:
    """`caller` shows round `round_index` in a page: the first time, remember when (their
    time shown counts from then). Raises NotFoundError."""
    now = now or utcnow()
    row = get_round(s, session_id, round_index)
    seen = s.scalars(
        select(RoundViewRow.id).where(
            RoundViewRow.round_id == row.id, RoundViewRow.annotator == caller.id
        )
    ).first()
    if seen is None:
        s.add(RoundViewRow(round_id=row.id, annotator=caller.id, shown_at=now))
        s.flush()
