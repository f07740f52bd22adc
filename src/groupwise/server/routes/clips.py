"""Clips and posters, by clip-store id only (HTTP Range supported for video seeking)."""

from fastapi import APIRouter, HTTPException
from fastapi.responses import FileResponse

from groupwise.clips.store import ClipNotFoundError, InvalidClipIdError
from groupwise.server.deps import Context
from groupwise.server.routes import ERRORS

router = APIRouter(prefix="/clips", tags=["clips"], responses=ERRORS)

IMMUTABLE = "public, max-age=31536000, immutable"
"""An id names its bytes forever (content-addressed), so browsers may cache for good."""


@router.get(
    "/{clip_id}",
    response_class=FileResponse,
    responses={
        200: {"content": {"video/mp4": {}, "image/jpeg": {}, "image/png": {}}},
        206: {"description": "a byte range of the clip"},
    },
)
def clip(clip_id: str, context: Context) -> FileResponse:
    """The MP4, JPEG or PNG stored under `clip_id`; 404 for anything else."""
    try:
        path = context.clips.path(clip_id)
        media_type = context.clips.media_type(clip_id)
    except (InvalidClipIdError, ClipNotFoundError):
        raise HTTPException(404, "there is no such clip") from None
    return FileResponse(path, media_type=media_type, headers={"Cache-Control": IMMUTABLE})
