"""The agent's learning curve."""

from fastapi import APIRouter

from groupwise.server import training_views
from groupwise.server.deps import Context, SessionId
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.training import TrainingCurve

router = APIRouter(prefix="/api/sessions/{session_id}", tags=["training"], responses=ERRORS)


@router.get("/training")
def training(session_id: SessionId, context: Context) -> TrainingCurve:
    """The points of the session's learning curve (PPO steps, true return, last refit, the
    pool's age) in time order, and the newest as a summary."""
    return training_views.training_curve(context.db, session_id)
