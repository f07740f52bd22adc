"""Dependency aliases, so handlers read as plain typed functions."""

from typing import Annotated

from fastapi import Depends, Path, Request

from groupwise.server.context import AppContext


def get_context(request: Request) -> AppContext:
    """The app's `AppContext` (set by `create_app`)."""
    context: AppContext = request.app.state.context
    return context


Context = Annotated[AppContext, Depends(get_context)]
SessionId = Annotated[str, Path(min_length=1, max_length=32, description="a session id")]
RoundIndex = Annotated[int, Path(ge=0, le=10_000, description="a round index")]
