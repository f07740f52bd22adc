"""Sessions: create, list, read, and the lifecycle actions (the owner's alone)."""

from fastapi import APIRouter, Depends, status

from groupwise.server import state
from groupwise.server.deps import Context, Me, SessionId, owner_only
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.sessions import SessionCreate, SessionState

router = APIRouter(prefix="/api/sessions", tags=["sessions"], responses=ERRORS)


@router.post("", status_code=status.HTTP_201_CREATED)
def create_session(request: SessionCreate, context: Context) -> SessionState:
    """Create a session; its first pool is prepared by the worker (phase `preparing`)."""
    return state.create_session(context, request)


@router.get("")
def list_sessions(context: Context, me: Me) -> list[SessionState]:
    """Every session, newest first (an annotator's: their own session)."""
    return state.list_states(context.db, context.viewer(me))


@router.get("/{session_id}")
def get_session(session_id: SessionId, context: Context, me: Me) -> SessionState:
    """The session's state: everything a reloaded page needs but the tree."""
    return state.read_state(context.db, session_id, context.viewer(me))


@router.post("/{session_id}/pause", dependencies=[Depends(owner_only("pause the round"))])
def pause(session_id: SessionId, context: Context) -> SessionState:
    """Pause the open round's timer (409 unless a round is open; the owner's)."""
    return state.pause(context, session_id)


@router.post("/{session_id}/resume", dependencies=[Depends(owner_only("resume the round"))])
def resume(session_id: SessionId, context: Context) -> SessionState:
    """Restart the paused timer (409 unless a round is open; the owner's)."""
    return state.resume(context, session_id)


@router.post("/{session_id}/end-round", dependencies=[Depends(owner_only("end the round"))])
def end_round(session_id: SessionId, context: Context) -> SessionState:
    """End the open round now; training starts (409 unless a round is open; the owner's)."""
    return state.close_open_round(context, session_id)


@router.post("/{session_id}/retry", dependencies=[Depends(owner_only("retry a failed step"))])
def retry(session_id: SessionId, context: Context) -> SessionState:
    """Re-queue the step that failed and restart the worker if needed (409 unless failed;
    the owner's)."""
    return state.retry(context, session_id)
