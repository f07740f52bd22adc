"""Connecting to the database: engines, pragmas, and read / write transactions.

SQLite (the default, ``DIR/groupwise.db``) is opened with, on every connection:

- ``journal_mode=WAL``: readers never block the writer nor it them, so the event streams
  and page reads go on while a judgement commits or the worker writes progress;
- ``foreign_keys=ON``: SQLite ignores ``ON DELETE CASCADE`` without it;
- ``busy_timeout``: a writer waits for the write lock instead of failing at once;
- ``synchronous=FULL``: a committed judgement survives a power cut, not only a crash.

Write transactions on SQLite start with ``BEGIN IMMEDIATE``: they take the write lock first,
so a read-then-write (numbering a judgement, bumping a revision) can never fail half-way
with ``SQLITE_BUSY`` when another writer committed in between (a deferred transaction's
upgrade from reader to writer does not wait on ``busy_timeout``). Within one process the
writers also queue on a `threading.Lock` before they ask SQLite: SQLite's busy handler
polls with growing sleeps (up to 100 ms), so 20 threads contending for the file lock saw
multi-second tails (benchmarks/submit_latency.py: p99 3.7 s before, 0.7 s after).
Reads use plain deferred transactions and never wait for writers (WAL). Other backends
(PostgreSQL) get ordinary transactions; the repositories lock the session row
(``SELECT … FOR UPDATE``) where SQLite's lock is not there.
"""

import threading
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event, inspect
from sqlalchemy.engine import make_url
from sqlalchemy.orm import Session as DbSession
from sqlalchemy.orm import sessionmaker

from groupwise.storage.models import Base

DATABASE_FILE = "groupwise.db"
BUSY_TIMEOUT_MS = 15_000
"""How long a SQLite writer waits for the lock (20 clients writing at once wait ~ms)."""


def sqlite_url(path: Path) -> str:
    """The SQLAlchemy URL of a SQLite file."""
    return f"sqlite:///{path.resolve()}"


def default_url(data_dir: Path) -> str:
    """``DIR/groupwise.db``, the database of a data directory unless `--db` names another."""
    return sqlite_url(data_dir / DATABASE_FILE)


class Database:
    """One database, opened for reads and writes.

    `read()` and `write()` are context managers yielding a SQLAlchemy `DbSession` whose
    transaction commits when the block ends normally and rolls back when it raises. Objects
    stay usable after the block (``expire_on_commit=False``). Thread-safe: each call gets its
    own `DbSession` and connection from the engines' pools.
    """

    def __init__(self, url: str, *, pool_size: int = 8) -> None:
        self.url = url
        self.is_sqlite = make_url(url).get_backend_name() == "sqlite"
        options: dict[str, Any] = {}
        if self.is_sqlite:
            options["connect_args"] = {"check_same_thread": False}
            options["pool_size"] = pool_size
            options["max_overflow"] = 32
        self.read_engine = self._engine(url, immediate=False, options=options)
        self.write_engine = (
            self._engine(url, immediate=True, options=options)
            if self.is_sqlite
            else self.read_engine
        )
        self._reader = sessionmaker(self.read_engine, expire_on_commit=False)
        self._writer = sessionmaker(self.write_engine, expire_on_commit=False)
        self._write_lock = threading.Lock() if self.is_sqlite else None

    def _engine(self, url: str, immediate: bool, options: dict[str, Any]) -> Engine:
        engine = create_engine(url, **options)
        if self.is_sqlite:
            event.listen(engine, "connect", _sqlite_connect)
            begin = "BEGIN IMMEDIATE" if immediate else "BEGIN"
            event.listen(engine, "begin", lambda conn: conn.exec_driver_sql(begin))
        return engine

    def create_schema(self) -> None:
        """Create every table that does not exist yet, and add the nullable columns a
        database made by an older version lacks (idempotent)."""
        Base.metadata.create_all(self.write_engine)
        add_missing_columns(self.write_engine)

    @contextmanager
    def read(self) -> Iterator[DbSession]:
        """A read transaction (it may write, but on SQLite a write may then fail busy)."""
        with self._reader() as s, s.begin():
            yield s

    @contextmanager
    def write(self) -> Iterator[DbSession]:
        """A write transaction: on SQLite it holds the write lock from its start."""
        with (
            self._write_lock or nullcontext(),
            self._writer() as s,
            s.begin(),
        ):
            yield s

    def dispose(self) -> None:
        """Close every pooled connection."""
        self.read_engine.dispose()
        if self.write_engine is not self.read_engine:
            self.write_engine.dispose()


def add_missing_columns(engine: Engine) -> list[str]:
    """Add the model's nullable columns missing from existing tables; "table.column" of each.

    A column added by a later version (``rounds.shown_at``) is nullable, so an older
    database gains it with a portable ``ALTER TABLE … ADD COLUMN`` and keeps its rows.
    Raises RuntimeError for a missing column that is not nullable (that needs a migration).
    """
    added: list[str] = []
    with engine.begin() as connection:
        existing = inspect(connection)
        for table in Base.metadata.sorted_tables:
            have = {column["name"] for column in existing.get_columns(table.name)}
            for column in table.columns:
                if column.name in have:
                    continue
                if not column.nullable:
                    raise RuntimeError(
                        f"the database lacks {table.name}.{column.name}; it was made by an "
                        "incompatible version of groupwise"
                    )
                kind = column.type.compile(dialect=engine.dialect)
                connection.exec_driver_sql(
                    f'ALTER TABLE "{table.name}" ADD COLUMN "{column.name}" {kind}'
                )
                added.append(f"{table.name}.{column.name}")
    return added


def _sqlite_connect(dbapi_connection: Any, record: Any) -> None:
    # pysqlite's own transaction handling would BEGIN lazily before DML only; we issue BEGIN
    # ourselves in the "begin" event (SQLAlchemy's documented recipe for SQLite).
    dbapi_connection.isolation_level = None
    cursor = dbapi_connection.cursor()
    try:
        cursor.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_MS}")
        cursor.execute("PRAGMA journal_mode=WAL")
        cursor.execute("PRAGMA foreign_keys=ON")
        cursor.execute("PRAGMA synchronous=FULL")
    finally:
        cursor.close()
