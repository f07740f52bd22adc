"""A round's pool: the tree, the pairwise suggestion edges, the next group suggestion; and
the page's report that it shows the round (which starts the round's timer)."""

from typing import Annotated

from fastapi import APIRouter, Query

from groupwise.server import pool_views, state
from groupwise.server.deps import Context, Me, RoundIndex, SessionId
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.rounds import Edge, RoundTree, SuggestionOut, SuggestionRequest
from groupwise.server.schemas.sessions import SessionState

router = APIRouter(prefix="/api/sessions/{session_id}/rounds", tags=["rounds"], responses=ERRORS)


@router.get("/{round_index}/tree")
def tree(session_id: SessionId, round_index: RoundIndex, context: Context) -> RoundTree:
    """The behaviour tree of the round, with clips, medoids and the compared behaviours."""
    return pool_views.round_tree(context, session_id, round_index)


@router.get("/{round_index}/edges")
def edges(
    session_id: SessionId,
    round_index: RoundIndex,
    context: Context,
    k: Annotated[int, Query(ge=0, le=2000)] = 100,
) -> list[Edge]:
    """The top-k pairwise suggestions (score in (0, 1], best first)."""
    return pool_views.round_edges(context.db, session_id, round_index, k)


@router.post("/{round_index}/next-suggestion")
def next_suggestion(
    session_id: SessionId,
    round_index: RoundIndex,
    context: Context,
    me: Me,
    request: SuggestionRequest | None = None,
) -> SuggestionOut:
    """The best group suggestion not answered yet, not excluded and not leased to another
    annotator (null when none); in a shared session it is leased to the caller for the
    session's `lease_s`."""
    exclude = request.exclude if request is not None else None
    return pool_views.next_suggestion(context.db, session_id, round_index, exclude, me)


@router.post("/{round_index}/shown")
def shown(session_id: SessionId, round_index: RoundIndex, context: Context, me: Me) -> SessionState:
    """The caller's page shows the open round: the first report starts its timer, the
    caller's first their time shown (409 for a round that is not the open one)."""
    return state.show_round(context, session_id, round_index, me)
