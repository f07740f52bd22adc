"""The end of a session: finish now, continue training, the final agent and its files."""

from fastapi import APIRouter, Depends
from fastapi.responses import FileResponse

from groupwise.agent_file.summary import AGENT_VIDEO, AGENT_ZIP
from groupwise.server import agent_views
from groupwise.server.deps import Context, SessionId, owner_only
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.agent import AgentOut, AgentPickIn, ContinueIn
from groupwise.server.schemas.sessions import SessionState

router = APIRouter(prefix="/api/sessions", tags=["agent"], responses=ERRORS)

NO_STORE = "no-cache"
"""The files change when training continues; the page asks with ?v=<round> anyway."""


@router.post("/{session_id}/finish", dependencies=[Depends(owner_only("finish the session"))])
def finish(session_id: SessionId, context: Context) -> SessionState:
    """No more rounds after the current one: the open round ends now (a round being
    prepared is dropped), then the final phase (409 when finishing, finished or failed)."""
    return agent_views.finish_now(context, session_id)


@router.post("/{session_id}/continue", dependencies=[Depends(owner_only("continue the training"))])
def continue_training(session_id: SessionId, request: ContinueIn, context: Context) -> SessionState:
    """Train a finished session again: `steps` more PPO steps on the frozen learned reward,
    or `rounds` more feedback rounds, then the final phase (409 unless finished)."""
    return agent_views.continue_training(context, session_id, request)


@router.get("/{session_id}/agent")
def agent(session_id: SessionId, context: Context) -> AgentOut:
    """The finished session's agent: its round, steps and true return per round (409
    before the session is finished, 404 for a session without one)."""
    return agent_views.agent(context, session_id)


@router.put("/{session_id}/agent/round", dependencies=[Depends(owner_only("choose the agent"))])
def pick_agent(session_id: SessionId, request: AgentPickIn, context: Context) -> AgentOut:
    """Hand over another round's policy: agent.zip and the summary are repacked from that
    round's checkpoint (404 for no such round, 409 before the session is finished or when
    the round's checkpoint is gone, with the reason). Default: the last round."""
    return agent_views.pick(context, session_id, request.round)


@router.get(
    "/{session_id}/agent/rounds/{round_index}.mp4",
    response_class=FileResponse,
    responses={200: {"content": {"video/mp4": {}}}, 206: {"description": "a byte range"}},
)
def round_video(session_id: SessionId, round_index: int, context: Context) -> FileResponse:
    """Round `round_index`'s greedy policy filmed for one episode: the clip the person picks
    the take-away agent by."""
    path = agent_views.round_video(context, session_id, round_index)
    return FileResponse(path, media_type="video/mp4", headers={"Cache-Control": NO_STORE})


@router.get(
    "/{session_id}/agent.mp4",
    response_class=FileResponse,
    responses={200: {"content": {"video/mp4": {}}}, 206: {"description": "a byte range"}},
)
def agent_video(session_id: SessionId, context: Context) -> FileResponse:
    """The final agent's video: one greedy episode at real speed."""
    path, _ = agent_views.agent_file(context, session_id, AGENT_VIDEO)
    return FileResponse(path, media_type="video/mp4", headers={"Cache-Control": NO_STORE})


@router.get(
    "/{session_id}/agent.zip",
    response_class=FileResponse,
    responses={200: {"content": {"application/zip": {}}}},
)
def agent_zip(session_id: SessionId, context: Context) -> FileResponse:
    """The final agent as one zip (policy, normaliser, reward ensemble, settings, README);
    `groupwise.load_agent` loads it."""
    path, summary = agent_views.agent_file(context, session_id, AGENT_ZIP)
    return FileResponse(
        path,
        media_type="application/zip",
        filename=f"groupwise-agent-{session_id}-round-{summary.round}.zip",
        headers={"Cache-Control": NO_STORE},
    )
