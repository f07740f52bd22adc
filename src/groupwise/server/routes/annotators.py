"""A session's annotators: the people its owner shares it with (docs/teams.md)."""

from typing import Annotated

from fastapi import APIRouter, Depends, Path, Request, Response, status

from groupwise.server import team_views
from groupwise.server.deps import Context, SessionId, owner_only
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.annotators import AnnotatorCreated, AnnotatorIn, AnnotatorOut

router = APIRouter(
    prefix="/api/sessions/{session_id}/annotators", tags=["annotators"], responses=ERRORS
)


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    dependencies=[Depends(owner_only("add annotators"))],
)
def add(
    session_id: SessionId, body: AnnotatorIn, context: Context, request: Request
) -> AnnotatorCreated:
    """Add an annotator: their token and their link, shown this once (409 for a name the
    session has; the owner's)."""
    return team_views.add(context, session_id, body, str(request.base_url))


@router.get("")
def team(session_id: SessionId, context: Context) -> list[AnnotatorOut]:
    """The owner (id "owner") and every annotator: comparisons, pairs, time shown, and
    their agreement with the others and with the reward model."""
    return team_views.team(context, session_id)


@router.delete(
    "/{annotator_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    response_class=Response,
    dependencies=[Depends(owner_only("remove annotators"))],
)
def remove(
    session_id: SessionId,
    annotator_id: Annotated[str, Path(min_length=1, max_length=32)],
    context: Context,
) -> Response:
    """Remove an annotator: their token stops working (401), their judgements stay."""
    team_views.remove(context, session_id, annotator_id)
    return Response(status_code=status.HTTP_204_NO_CONTENT)
