"""`create_app(config)`: the FastAPI app of the interactive web UI (docs/app.md).

No import-time state: everything lives in the `AppContext` that `create_app` makes and keeps
in ``app.state.context``. The app's lifespan runs the worker supervisor (when
`AppConfig.start_worker`); handlers only validate, store and read.

Errors are JSON ``{"detail": "one sentence"}``: the repositories' refusals map to 404 / 409 /
422 (`groupwise.storage.errors`), FastAPI's validation errors are flattened into one
sentence naming each bad field, and an unexpected exception is logged and answered 500
without internals.
"""

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.middleware.trustedhost import TrustedHostMiddleware

from groupwise.server.config import AppConfig
from groupwise.server.context import AppContext
from groupwise.server.routes import clips, events, judgements, meta, pairwise, rounds, sessions
from groupwise.server.routes import transfer as transfer_routes
from groupwise.server.routes.frontend import mount_frontend
from groupwise.server.security import GuardMiddleware, trusted_hosts
from groupwise.server.transfer import UnsupportedMediaError
from groupwise.storage import ConflictError, InvalidError, NotFoundError, StorageError

log = logging.getLogger(__name__)

STATUS: dict[type[StorageError], int] = {
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
        try:
            yield
        finally:
            if task is not None:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            await asyncio.to_thread(context.supervisor.stop)
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
    app.add_middleware(GuardMiddleware, token=config.token, max_body_bytes=config.max_body_bytes)
    # Added last, so it runs first: a foreign Host is refused before anything else is checked.
    app.add_middleware(
        TrustedHostMiddleware, allowed_hosts=trusted_hosts(config.allowed_hosts), www_redirect=False
    )
    app.add_exception_handler(StorageError, _storage_error)  # type: ignore[arg-type]
    app.add_exception_handler(RequestValidationError, _validation_error)  # type: ignore[arg-type]
    app.add_exception_handler(Exception, _unexpected_error)
    for module in (meta, sessions, transfer_routes, rounds, judgements, pairwise, events, clips):
        app.include_router(module.router)
    mount_frontend(app, config.static_root)
    return app


def _storage_error(request: Request, error: StorageError) -> JSONResponse:
    status = next((code for kind, code in STATUS.items() if isinstance(error, kind)), 400)
    return JSONResponse({"detail": str(error)}, status_code=status)


def _validation_error(request: Request, error: RequestValidationError) -> JSONResponse:
    parts = []
    for item in error.errors()[:10]:
        where = ".".join(str(p) for p in item.get("loc", ()) if p != "body") or "body"
        parts.append(f"{where}: {item.get('msg', 'invalid')}")
    return JSONResponse({"detail": "; ".join(parts) or "invalid request"}, status_code=422)


def _unexpected_error(request: Request, error: Exception) -> JSONResponse:
    log.exception("unexpected error in %s %s", request.method, request.url.path)
    return JSONResponse({"detail": "internal error; see the server log"}, status_code=500)
