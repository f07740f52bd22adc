"""Clips and posters, by clip-store id only (HTTP Range supported for video seeking).

An id published on demand (`clips.on_demand`) is rendered from its recipe on the first
request, by render processes of the server (or Ray tasks with ``serve --ray``), and is a
file from then on.
"""

import logging
import threading
from typing import Annotated, Any

from fastapi import APIRouter, Depends, HTTPException, Request
from fastapi.responses import FileResponse

from groupwise.clips.on_demand import (
    OnDemandClips,
    RenderBusyError,
    RenderFailedError,
    local_renderer,
    ray_renderer,
)
from groupwise.clips.store import ClipNotFoundError, InvalidClipIdError
from groupwise.server.context import AppContext
from groupwise.server.deps import Context
from groupwise.server.routes import ERRORS

log = logging.getLogger(__name__)

router = APIRouter(prefix="/clips", tags=["clips"], responses=ERRORS)

IMMUTABLE = "public, max-age=31536000, immutable"
"""An id names its bytes forever (content- or recipe-addressed), so browsers may cache for
good."""

_MAKING = threading.Lock()


def renderer(request: Request, context: Context) -> OnDemandClips:
    """The app's on-demand renderer, made on first use and kept in ``app.state``; closed
    when the app stops (its lifespan). A served app makes it at startup (`start_renderer`)."""
    return app_renderer(request.app.state, context)


def start_renderer(state: Any, context: AppContext) -> None:
    """Make the app's renderer and start its processes, so that the first clip a person
    asks for does not wait for them to start (10-11 s on a busy 2-core machine).

    Only a head start: a renderer that cannot start now (no process can be started, say)
    is logged and the server serves; the first clip asked for tries again (a broken
    process pool is started anew, `clips.on_demand.ProcessBackend`). Raising here failed
    the app's startup, which left the server process bound but not listening, waiting
    for its training worker at exit while the worker trained on."""
    try:
        app_renderer(state, context).backend.start()
    except Exception:
        log.exception("the clip render processes did not start; the first clip starts them")


def app_renderer(state: Any, context: AppContext) -> OnDemandClips:
    """The renderer kept in the app's `state` (made on first use)."""
    with _MAKING:
        made: OnDemandClips | None = getattr(state, "clip_renderer", None)
        if made is None:
            config = context.config
            if config.ray_address is not None:
                made = ray_renderer(context.clips, config.ray_address)  # the cluster's CPUs
            else:
                made = local_renderer(context.clips, config.clip_workers)
            state.clip_renderer = made
    return made


Renderer = Annotated[OnDemandClips, Depends(renderer)]


@router.get(
    "/{clip_id}",
    response_class=FileResponse,
    responses={
        200: {"content": {"video/mp4": {}, "image/jpeg": {}, "image/png": {}}},
        206: {"description": "a byte range of the clip"},
        500: {"description": "the clip could not be rendered"},
        503: {"description": "too many clips asked for at once; ask again"},
    },
)
async def clip(clip_id: str, clips: Renderer) -> FileResponse:
    """The MP4, JPEG or PNG stored under `clip_id` (rendered first when it is published on
    demand); 404 for anything else."""
    try:
        path = await clips.file(clip_id)
        media_type = clips.store.media_type(clip_id)
    except (InvalidClipIdError, ClipNotFoundError):
        raise HTTPException(404, "there is no such clip") from None
    except RenderBusyError as error:
        raise HTTPException(503, str(error)) from None
    except RenderFailedError as error:
        raise HTTPException(500, str(error)) from None
    return FileResponse(path, media_type=media_type, headers={"Cache-Control": IMMUTABLE})
