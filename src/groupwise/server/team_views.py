"""A session's team as the page sees it: adding, listing and removing annotators
(docs/teams.md; `storage.annotators`, `storage.team`)."""

from groupwise.server.context import AppContext
from groupwise.server.schemas.annotators import AnnotatorCreated, AnnotatorIn, AnnotatorOut
from groupwise.server.state import annotator_out, close_if_due
from groupwise.storage import InvalidError
from groupwise.storage import annotators as repo
from groupwise.storage.models import utcnow
from groupwise.storage.sessions import get_session
from groupwise.storage.team import team_stats


def link(base_url: str, session_id: str, token: str) -> str:
    """The page of a session for the holder of `token`: the app's URL (`base_url`, the
    server's root as the request reached it) with ``?session=…&token=…``, as `groupwise
    serve` prints the owner's."""
    return f"{base_url.rstrip('/')}/?session={session_id}&token={token}"


def add(
    context: AppContext, session_id: str, request: AnnotatorIn, base_url: str
) -> AnnotatorCreated:
    """Add an annotator with a new token. Raises NotFoundError, InvalidError (the name),
    ConflictError (a name already there)."""
    with context.db.write() as s:
        added = repo.add_annotator(s, session_id, request.name)
    return AnnotatorCreated(
        id=added.id,
        name=added.name,
        token=added.token,
        link=link(base_url, session_id, added.token),
    )


def team(context: AppContext, session_id: str) -> list[AnnotatorOut]:
    """The owner and the present annotators with their counters and agreement."""
    close_if_due(context.db, session_id)
    with context.db.read() as s:
        session = get_session(s, session_id)
        stats = team_stats(s, session, utcnow(), context.round_scores)
    return [annotator_out(row) for row in stats]


def remove(context: AppContext, session_id: str, annotator_id: str) -> None:
    """Remove an annotator (their token stops working; their judgements stay). Raises
    NotFoundError, InvalidError (the owner)."""
    if annotator_id == repo.OWNER:
        raise InvalidError("the owner cannot be removed from their session")
    with context.db.write() as s:
        repo.remove_annotator(s, session_id, annotator_id)
