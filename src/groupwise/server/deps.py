"""Dependency aliases, so handlers read as plain typed functions."""

from collections.abc import Callable
from typing import Annotated

from fastapi import Depends, Path, Request

from groupwise.server.context import AppContext
from groupwise.storage import ForbiddenError
from groupwise.storage.annotators import OWNER_CALLER, Caller


def get_context(request: Request) -> AppContext:
    """The app's `AppContext` (set by `create_app`)."""
    context: AppContext = request.app.state.context
    return context


def get_caller(request: Request) -> Caller:
    """Who sends the request, as `GuardMiddleware` found (docs/teams.md)."""
    caller = request.scope.get("state", {}).get("caller", OWNER_CALLER)
    assert isinstance(caller, Caller)
    return caller


def owner_only(action: str) -> Callable[[Caller], None]:
    """A dependency refusing an annotator (403) what only the session's owner may do:
    `action` completes "only the session's owner can …"."""

    def check(caller: Annotated[Caller, Depends(get_caller)]) -> None:
        if not caller.is_owner:
            raise ForbiddenError(
                f"only the session's owner can {action}; {caller.name} is an annotator"
            )

    return check


Context = Annotated[AppContext, Depends(get_context)]
Me = Annotated[Caller, Depends(get_caller)]
SessionId = Annotated[str, Path(min_length=1, max_length=32, description="a session id")]
RoundIndex = Annotated[int, Path(ge=0, le=10_000, description="a round index")]
