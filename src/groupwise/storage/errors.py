"""What the repositories raise for requests they refuse; each message is one clear sentence.

The server maps them to HTTP statuses (403, 404, 409, 422) with the message as ``detail``.
"""


class StorageError(Exception):
    """A refused request; `str(error)` is the sentence shown to the user."""


class NotFoundError(StorageError):
    """An unknown session, round, judgement or behaviour (HTTP 404)."""


class ForbiddenError(StorageError):
    """The caller may not do this: another annotator's judgement, or an owner's action
    (HTTP 403)."""


class ConflictError(StorageError):
    """The request does not fit the session's current state (HTTP 409)."""


class InvalidError(StorageError):
    """The request is well-formed but its content is not acceptable (HTTP 422)."""


def check_text(what: str, value: str) -> str:
    """`value`, unless it holds a NUL character: PostgreSQL's text cannot store one and no
    name, id or annotator needs one, so both backends refuse it alike. Raises InvalidError.
    """
    if "\x00" in value:
        raise InvalidError(f"{what} contains a NUL character")
    return value
