"""The pairwise baseline: the pair to ask now and the following one; skipping a pair."""

from fastapi import APIRouter

from groupwise.server import pool_views
from groupwise.server.deps import Context, Me, SessionId
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.pairwise import PairSkip, PairwiseNext

router = APIRouter(
    prefix="/api/sessions/{session_id}/pairwise", tags=["pairwise"], responses=ERRORS
)


@router.get("/next")
def next_pair(session_id: SessionId, context: Context, me: Me) -> PairwiseNext:
    """The next unanswered pair of the open round's queue and the one after it, neither
    leased to another annotator; in a shared session the first is leased to the caller."""
    return pool_views.pairwise_next(context, session_id, me)


@router.post("/skip")
def skip(session_id: SessionId, request: PairSkip, context: Context, me: Me) -> PairwiseNext:
    """Skip a pair of the queue (it is not asked again this round); the next pairs."""
    return pool_views.skip_pair(context, session_id, request, me)
