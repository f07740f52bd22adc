"""Export a session (JSONL or Parquet) and import an export as a new session."""

from typing import Annotated, Literal

import anyio
from fastapi import APIRouter, Query, Request, Response, status

from groupwise.server import transfer
from groupwise.server.deps import Context, SessionId
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.sessions import SessionState

router = APIRouter(prefix="/api/sessions", tags=["export"], responses=ERRORS)


@router.get(
    "/{session_id}/export",
    response_class=Response,
    responses={
        200: {
            "content": {"application/x-ndjson": {}, "application/vnd.apache.parquet": {}},
            "description": "the session's judgements and pairs",
        }
    },
)
def export(
    session_id: SessionId,
    context: Context,
    format: Annotated[Literal["jsonl", "parquet"], Query()] = "jsonl",
    states: Annotated[
        bool,
        Query(
            description="also the compared behaviours' observations and actions (and, once "
            "the session has finished, true rewards); docs/export.md"
        ),
    ] = False,
) -> Response:
    """The session's judgements and pairs as a file download."""
    file = transfer.export_file(
        context.db,
        session_id,
        format,
        context.data_dir if states else None,
        context.round_scores,
    )
    return Response(
        file.body,
        media_type=file.media_type,
        headers={"Content-Disposition": f'attachment; filename="{file.filename}"'},
    )


@router.post(
    "/import",
    status_code=status.HTTP_201_CREATED,
    responses={415: {"description": "the body is not JSONL or Parquet"}},
    openapi_extra={
        "requestBody": {
            "required": True,
            "content": {
                "application/x-ndjson": {"schema": {"type": "string"}},
                "application/vnd.apache.parquet": {
                    "schema": {"type": "string", "format": "binary"}
                },
            },
        }
    },
)
async def import_session(request: Request, context: Context) -> SessionState:
    """A new, finished session holding an export's judgements and pairs."""
    body = await request.body()
    content_type = request.headers.get("content-type", "")
    # the body is read asynchronously; parsing and storing run on a worker thread
    return await anyio.to_thread.run_sync(
        transfer.import_file, context.db, body, content_type, context.data_dir
    )
