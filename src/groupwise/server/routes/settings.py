"""Settings: what a new session would store, without creating it (the New-session page)."""

from fastapi import APIRouter

from groupwise.server import state
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.sessions import SessionCreate
from groupwise.storage.settings import SessionSettings

router = APIRouter(prefix="/api/settings", tags=["settings"], responses=ERRORS)


@router.post("/resolve")
def resolve_settings(request: SessionCreate) -> SessionSettings:
    """The settings `POST /api/sessions` would store for this body: the env's defaults with
    the given settings (L in steps, `clip_seconds` and `final_steps` resolved); 422 with the
    same sentence when it would refuse the env or the settings. Nothing is created.

    A POST, not a GET, because checking a ``module:Env-v0`` id imports that module: only the
    app's own page and scripts may make the server do that (docs/app.md, Security)."""
    return state.check_new_session(request.env, request.settings)[1]
