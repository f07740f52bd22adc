"""The app's database: schema, connections and repositories (docs/app.md, "Processes").

SQLAlchemy 2 on SQLite (WAL) by default, portable to PostgreSQL. Repository functions take
an open SQLAlchemy session from `Database.read()` / `Database.write()` (imported as
`DbSession`, since "session" here means an app session, a `SessionRow`) and leave the
commit to that block, so a request is one transaction:

    db = Database(default_url(data_dir)); db.create_schema()
    with db.write() as s:
        record, created = add_judgement(s, session_id, judgement)
    # committed here, before the HTTP answer

Modules: `models` (tables), `database` (engines, pragmas), `settings` (session settings),
`sessions` (session rows: create, get, list), `phases` (phase names, the open-round guard),
`lifecycle` (phase changes: open, close, train, final, fail, retry), `timer` (the round
timer: shown, pause, resume, due), `progress` (the worker's progress line), `counts`
(comparisons and pairs), `ending` ("Finish now", "Continue training"),
`rounds` (pools, suggestions, pairwise queue),
`judging` (store, retry, undo), `judgements` (the records: list, a round's), `annotators`
(the people a session is shared with, their tokens and views), `team` (their counters and
agreement), `export` (a session to its export and back), `export_format` (the export's
lines), `export_jsonl` / `export_parquet` (the export as JSONL / Parquet).
"""

from groupwise.storage.database import DATABASE_FILE, Database, default_url, sqlite_url
from groupwise.storage.errors import (
    ConflictError,
    ForbiddenError,
    InvalidError,
    NotFoundError,
    StorageError,
)
from groupwise.storage.settings import SessionSettings

__all__ = [
    "DATABASE_FILE",
    "ConflictError",
    "Database",
    "ForbiddenError",
    "InvalidError",
    "NotFoundError",
    "SessionSettings",
    "StorageError",
    "default_url",
    "sqlite_url",
]
