"""The event stream of a session."""

from typing import Annotated

from fastapi import APIRouter, Header
from fastapi.responses import StreamingResponse

from groupwise.server.deps import Context, Me, SessionId
from groupwise.server.events import session_events
from groupwise.server.routes import ERRORS
from groupwise.server.state import read_state

router = APIRouter(prefix="/api/sessions/{session_id}", tags=["events"], responses=ERRORS)


@router.get(
    "/events",
    response_class=StreamingResponse,
    responses={200: {"content": {"text/event-stream": {}}, "description": "the events"}},
)
def events(
    session_id: SessionId,
    context: Context,
    me: Me,
    last_event_id: Annotated[int | None, Header(ge=0, le=2**62)] = None,
) -> StreamingResponse:
    """Server-sent events: `state` (as the caller sees it), `judgement` (everyone's),
    `round`, `training`, and keep-alive comments."""
    read_state(context.db, session_id)  # 404 before the stream starts
    config = context.config
    stream = session_events(
        context.db,
        session_id,
        config.events_poll_s,
        config.keepalive_s,
        last_event_id,
        context.viewer(me),
    )
    return StreamingResponse(
        stream,
        media_type="text/event-stream",
        headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"},
    )
