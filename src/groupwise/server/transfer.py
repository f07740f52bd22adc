"""Export and import of sessions over HTTP (the files: `groupwise.storage.export_jsonl` and
`groupwise.storage.export_parquet`)."""

from dataclasses import dataclass
from pathlib import Path

from groupwise.server.schemas.sessions import SessionState
from groupwise.server.state import read_state
from groupwise.storage import Database, InvalidError
from groupwise.storage import export as repo
from groupwise.storage.export_jsonl import from_jsonl, to_jsonl
from groupwise.storage.export_parquet import from_parquet, to_parquet
from groupwise.storage.phases import FINISHED
from groupwise.storage.sessions import get_session
from groupwise.storage.team import ScoreSource

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


def export_file(
    db: Database,
    session_id: str,
    fmt: str,
    states_from: Path | None = None,
    scores: ScoreSource | None = None,
) -> ExportFile:
    """The session's export in `fmt` ("jsonl" or "parquet"); with `states_from` (the data
    directory) the compared behaviours' arrays too, and their true rewards once the session
    has finished (never while a person may still judge); `scores`: the reward model's
    predictions for the annotators' model agreement. Raises NotFoundError."""
    media_type, write = FORMATS[fmt]
    with db.read() as s:
        states = None
        if states_from is not None:
            finished = get_session(s, session_id).phase == FINISHED
            states = repo.StatesExport(states_from, true_rewards=finished)
        export = repo.export_session(s, session_id, states, scores)
    return ExportFile(write(export), media_type, f"{session_id}.{fmt}")


def import_file(db: Database, body: bytes, content_type: str, data_dir: Path) -> SessionState:
    """Import an export into a new, finished session (its states, if any, into `data_dir`).
    Raises InvalidError."""
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
        session_id = repo.import_session(s, export, data_dir=data_dir).id
    return read_state(db, session_id)


class UnsupportedMediaError(InvalidError):
    """The import's content type is not one of `IMPORT_TYPES` (HTTP 415)."""
