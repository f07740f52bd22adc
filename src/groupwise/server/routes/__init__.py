"""One router per resource; handlers parse, call one service function, and return."""

from typing import Any

from groupwise.server.schemas.base import ErrorOut

ERRORS: dict[int | str, dict[str, Any]] = {
    code: {"model": ErrorOut, "description": text}
    for code, text in (
        (400, "bad request"),
        (401, "missing or wrong token"),
        (403, "not the caller's to do: another annotator's, or the owner's alone"),
        (404, "unknown session, round or judgement"),
        (409, "not possible in the session's current phase"),
        (413, "body too large"),
        (422, "invalid input"),
    )
}
"""The error answers every API route may give, for the OpenAPI schema."""
