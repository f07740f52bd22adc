"""Export and import of sessions over HTTP (formats: `groupwise.storage.export_format`)."""

from dataclasses import dataclass

from groupwise.server import schemas
from groupwise.server.state import read_state
from groupwise.storage import Database, InvalidError
from groupwise.storage import export as repo
from groupwise.storage.export_format import from_jsonl, from_parquet, to_jsonl, to_parquet

FORMATS = {
    "jsonl": ("application/x-ndjson", to_jsonl),
    "parquet": ("application/vnd.apache.parquet", to_parquet),
}
"""Export format → (media type, writer)."""
IMPORT_TYPES = {
    "application/x-ndjson": from_jsonl,
    "application/jsonl": from_jsonl,
    "application/json": from_jsonl,
    "application/vnd.apache.parquet": from_parquet,
    "application/octet-stream": from_parquet,
}
"""Content types an import accepts → parser. Form and text types are refused, so a page on
another site cannot post an import with a plain HTML form."""


@dataclass(frozen=True)
class ExportFile:
    body: bytes
    media_type: str
    filename: str


def export_file(db: Database, session_id: str, fmt: str) -> ExportFile:
    """The session's export in `fmt` ("jsonl" or "parquet"). Raises NotFoundError."""
    media_type, write = FORMATS[fmt]
    with db.read() as s:
        export = repo.export_session(s, session_id)
    return ExportFile(write(export), media_type, f"{session_id}.{fmt}")


def import_file(db: Database, body: bytes, content_type: str) -> schemas.SessionState:
    """Import an export into a new, finished session. Raises InvalidError."""
    kind = content_type.split(";", 1)[0].strip().lower()
    parse = IMPORT_TYPES.get(kind)
    if parse is None:
        raise UnsupportedMediaError(
            f"send the export as {' or '.join(sorted(IMPORT_TYPES))}, not {kind or 'nothing'}"
        )
    if not body:
        raise InvalidError("the body is empty")
    export = parse(body)
    with db.write() as s:
        session_id = repo.import_session(s, export).id
    return read_state(db, session_id)


class UnsupportedMediaError(InvalidError):
    """The import's content type is not one of `IMPORT_TYPES` (HTTP 415)."""
