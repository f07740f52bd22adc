"""`create_app(config)`: the FastAPI app of the interactive web UI (docs/app.md).

No import-time state: everything lives in the `AppContext` that `create_app` makes and keeps
in ``app.state.context``. The app's lifespan runs the worker supervisor (when
`AppConfig.start_worker`); handlers only validate, store and read.

Errors are JSON ``{"detail": "one sentence"}``: the repositories' refusals map to 404 / 409 /
422 (`groupwise.storage.errors`), FastAPI's validation errors are flattened into one
sentence naming each bad field (a body that is not JSON: 400 naming where the decoder
stopped; a body that is not UTF-8: 400 naming the first bad byte), and an unexpected
exception is logged and answered 500 without internals.
"""

import asyncio
import contextlib
import json
import logging
from collections.abc import AsyncIterator, Callable
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException
from starlette.middleware.trustedhost import TrustedHostMiddleware

from groupwise.server.config import AppConfig
from groupwise.server.context import AppContext
from groupwise.server.routes import (
    agent,
    annotators,
    clips,
    events,
    judgements,
    meta,
    pairwise,
    rounds,
    sessions,
    training,
)
from groupwise.server.routes import settings as settings_routes
from groupwise.server.routes import transfer as transfer_routes
from groupwise.server.routes.clips import start_renderer
from groupwise.server.routes.frontend import mount_frontend
from groupwise.server.security import (
    JSON_TYPE,
    STATE_CHANGING,
    GuardMiddleware,
    trusted_hosts,
)
from groupwise.server.transfer import UnsupportedMediaError
from groupwise.storage import (
    ConflictError,
    ForbiddenError,
    InvalidError,
    NotFoundError,
    StorageError,
)

log = logging.getLogger(__name__)

STATUS: dict[type[StorageError], int] = {
    ForbiddenError: 403,
    NotFoundError: 404,
    ConflictError: 409,
    UnsupportedMediaError: 415,
    InvalidError: 422,
}
"""Repository refusal → HTTP status (the most specific class that matches wins)."""


def create_app(config: AppConfig) -> FastAPI:
    """The app for `config` (its database tables are created if missing)."""
    context = AppContext.open(config)

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        task = asyncio.create_task(context.supervisor.run()) if config.start_worker else None
        try:  # from here on a failed startup stops the worker too
            if config.start_worker:  # a served app: its clip renderer starts with it
                await asyncio.to_thread(start_renderer, app.state, context)
            yield
        finally:
            if task is not None:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            await asyncio.to_thread(context.supervisor.stop)
            # the clip render processes: a pool left open leaks its semaphores (issue 40)
            renderer = getattr(app.state, "clip_renderer", None)
            if renderer is not None:
                await asyncio.to_thread(renderer.close)
            context.db.dispose()

    app = FastAPI(
        title="groupwise",
        summary="RLHF with interactive groupwise comparison: the web UI's API",
        version="1",
        lifespan=lifespan,
        openapi_url="/api/openapi.json",
        docs_url="/api/docs",
        redoc_url=None,
    )
    app.state.context = context
    for module in (
        meta,
        settings_routes,
        sessions,
        transfer_routes,
        rounds,
        judgements,
        annotators,
        pairwise,
        events,
        training,
        clips,
        agent,
    ):
        app.include_router(module.router)
    app.openapi = _with_guard_responses(app.openapi)  # type: ignore[method-assign]  # FastAPI's documented override
    app.add_middleware(
        GuardMiddleware,
        token=config.token,
        max_body_bytes=config.max_body_bytes,
        own_body_types=own_body_types(app),
        identify=context.identify,
    )
    # Added last, so it runs first: a foreign Host is refused before anything else is checked.
    app.add_middleware(
        TrustedHostMiddleware, allowed_hosts=trusted_hosts(config.allowed_hosts), www_redirect=False
    )
    app.add_exception_handler(StorageError, _storage_error)  # type: ignore[arg-type]  # Starlette types handlers on Exception
    app.add_exception_handler(RequestValidationError, _validation_error)  # type: ignore[arg-type]  # as above
    app.add_exception_handler(HTTPException, _http_error)  # type: ignore[arg-type]  # as above
    app.add_exception_handler(Exception, _unexpected_error)
    mount_frontend(app, config.static_root)
    return app


def own_body_types(app: FastAPI) -> frozenset[str]:
    """Paths whose documented request body names no JSON type: those routes take other
    bodies (the import: JSONL, Parquet) and check the content type themselves.

    Read from the OpenAPI schema, the routes' own declaration. A path with parameters would
    need a pattern; none takes another body type, and one that did would answer 415 (loudly).
    """
    paths = set()
    for path, operations in app.openapi()["paths"].items():
        for operation in operations.values():
            content = operation.get("requestBody", {}).get("content", {})
            if content and JSON_TYPE not in content:
                paths.add(path)
    return frozenset(paths)


GUARD_RESPONSES = {
    "403": "a state change from another site (Sec-Fetch-Site or Origin)",
    "415": "a body that is not application/json",
}
"""What `GuardMiddleware` may answer to any state change, for the OpenAPI schema."""


def _with_guard_responses(openapi: Callable[[], dict[str, Any]]) -> Callable[[], dict[str, Any]]:
    """FastAPI's `openapi` with `GUARD_RESPONSES` added to every state-changing operation
    (the middleware answers them, so no route declares them itself)."""

    def schema() -> dict[str, Any]:
        document = openapi()  # built once and cached by FastAPI; amended in place
        error = {"application/json": {"schema": {"$ref": "#/components/schemas/ErrorOut"}}}
        for operations in document["paths"].values():
            for method, operation in operations.items():
                if method.upper() in STATE_CHANGING:
                    for code, text in GUARD_RESPONSES.items():
                        responses = operation.setdefault("responses", {})
                        responses.setdefault(code, {"description": text, "content": error})
        return document

    return schema


def _storage_error(request: Request, error: StorageError) -> JSONResponse:
    status = next((code for kind, code in STATUS.items() if isinstance(error, kind)), 400)
    return JSONResponse({"detail": str(error)}, status_code=status)


def _validation_error(request: Request, error: RequestValidationError) -> JSONResponse:
    malformed = next((e for e in error.errors() if e.get("type") == "json_invalid"), None)
    if malformed is not None:
        return JSONResponse({"detail": _json_error(malformed, error.body)}, status_code=400)
    parts = []
    for item in error.errors()[:10]:
        where = ".".join(str(p) for p in item.get("loc", ()) if p != "body") or "body"
        parts.append(f"{where}: {item.get('msg', 'invalid')}")
    return JSONResponse({"detail": "; ".join(parts) or "invalid request"}, status_code=422)


def _json_error(item: dict[str, Any], document: Any) -> str:
    """One sentence for FastAPI's "JSON decode error" (whose ``loc`` is the character offset
    and ``ctx`` the decoder's message), with the line and column the decoder would name."""
    reason = str(item.get("ctx", {}).get("error", "invalid JSON"))
    loc = item.get("loc", ())
    position = loc[-1] if loc else None
    if isinstance(document, str) and isinstance(position, int):
        where = json.JSONDecodeError(reason, document, position)
        reason = f"{reason} at line {where.lineno} column {where.colno}"
    return f"request body is not valid JSON: {reason}"


async def _http_error(request: Request, error: HTTPException) -> Response:
    """FastAPI's own answer, but for a JSON body that is not UTF-8: FastAPI answers any body
    it cannot decode with a vague 400 ("There was an error parsing the body"); this one says
    which byte is wrong."""
    cause = error.__cause__
    if error.status_code == 400 and isinstance(cause, UnicodeDecodeError):
        byte, offset = cause.object[cause.start], cause.start
        detail = (
            f"request body is not valid UTF-8 JSON: invalid byte 0x{byte:02x} at offset {offset}"
        )
        return JSONResponse({"detail": detail}, status_code=400)
    return await http_exception_handler(request, error)


def _unexpected_error(request: Request, error: Exception) -> JSONResponse:
    log.exception("unexpected error in %s %s", request.method, request.url.path)
    return JSONResponse({"detail": "internal error; see the server log"}, status_code=500)
