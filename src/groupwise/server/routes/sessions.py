"""Sessions: create, list, read, and the lifecycle actions."""

from fastapi import APIRouter, status

from groupwise.server import state
from groupwise.server.deps import Context, SessionId
from groupwise.server.routes import ERRORS
from groupwise.server.schemas import SessionCreate, SessionState

router = APIRouter(prefix="/api/sessions", tags=["sessions"], responses=ERRORS)


@router.post("", status_code=status.HTTP_201_CREATED)
def create_session(request: SessionCreate, context: Context) -> SessionState:
    """Create a session; its first pool is prepared by the worker (phase `preparing`)."""
    return state.create_session(context, request)


@router.get("")
def list_sessions(context: Context) -> list[SessionState]:
    """Every session, newest first."""
    return state.list_states(context.db)


@router.get("/{session_id}")
def get_session(session_id: SessionId, context: Context) -> SessionState:
    """The session's state: everything a reloaded page needs but the tree."""
    return state.read_state(context.db, session_id)


@router.post("/{session_id}/pause")
def pause(session_id: SessionId, context: Context) -> SessionState:
    """Pause the open round's timer (409 unless a round is open)."""
    return state.pause(context.db, session_id)


@router.post("/{session_id}/resume")
def resume(session_id: SessionId, context: Context) -> SessionState:
    """Restart the paused timer (409 unless a round is open)."""
    return state.resume(context.db, session_id)


@router.post("/{session_id}/end-round")
def end_round(session_id: SessionId, context: Context) -> SessionState:
    """End the open round now; training starts (409 unless a round is open)."""
    return state.end_round(context, session_id)


@router.post("/{session_id}/retry")
def retry(session_id: SessionId, context: Context) -> SessionState:
    """Re-queue the step that failed and restart the worker if needed (409 unless failed)."""
    return state.retry(context, session_id)
