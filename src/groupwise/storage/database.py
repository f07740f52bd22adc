"""Connecting to the database: engines, pragmas, and read / write transactions.

Two backends, one behaviour: SQLite (the default, ``DIR/groupwise.db``) and PostgreSQL
(``--db postgresql+psycopg://…``, the `postgres` extra; a team's shared server, README).
Both run every write transaction alone: one writer at a time, readers never blocked.

SQLite is opened with, on every connection:

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
Reads use plain deferred transactions and never wait for writers (WAL).

PostgreSQL (READ COMMITTED, its default) gets the same one-writer rule from a transaction-
level advisory lock that every write transaction takes first (``pg_advisory_xact_lock``,
released by its commit or rollback), across all processes and hosts that share the
database: the repositories' read-then-write steps (numbering a judgement, counting the
round's judgements, bumping the session's revision) then see every earlier commit, as on
SQLite, instead of racing as two READ COMMITTED transactions would. The waiting writers
queue in the server, not in a polling loop, and a judgement commits in about a millisecond,
so the lock costs a shared team server little (benchmarks/submit_latency.py ``--db``).
The repositories also lock the session row (``SELECT … FOR UPDATE``) before they change it.
Reads are plain transactions and never wait for writers (MVCC).
"""

import threading
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from os import PathLike
from pathlib import Path
from typing import Any

from sqlalchemy import Connection, Engine, create_engine, event, inspect, text
from sqlalchemy.engine import make_url
from sqlalchemy.orm import Session as DbSession
from sqlalchemy.orm import sessionmaker

from groupwise.storage.models import Base

DATABASE_FILE = "groupwise.db"
BUSY_TIMEOUT_MS = 15_000
"""How long a SQLite writer waits for the lock (20 clients writing at once wait ~ms)."""
WRITE_LOCK = 0x67726F7570  # "group"
"""The PostgreSQL advisory lock key every write transaction holds (module docstring)."""
_TAKE_WRITE_LOCK = text("SELECT pg_advisory_xact_lock(:key)").bindparams(key=WRITE_LOCK)


def sqlite_url(path: str | PathLike[str]) -> str:
    """The SQLAlchemy URL of a SQLite file (a str or a Path)."""
    return f"sqlite:///{Path(path).resolve()}"


def default_url(data_dir: str | PathLike[str]) -> str:
    """``DIR/groupwise.db``, the database of a data directory (a str or a Path) unless
    `--db` names another."""
    return sqlite_url(Path(data_dir) / DATABASE_FILE)


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
        # the server's request threads (up to 40) each hold a connection while they wait
        options: dict[str, Any] = {"pool_size": pool_size, "max_overflow": 32}
        if self.is_sqlite:
            options["connect_args"] = {"check_same_thread": False}
        else:
            # a shared server restarts (or drops idle connections) without telling us
            options["pool_pre_ping"] = True
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
        with self.write_engine.begin() as connection:
            if not self.is_sqlite:  # two servers starting at once would race to create
                connection.execute(_TAKE_WRITE_LOCK)
            Base.metadata.create_all(connection)
            add_missing_columns(connection)

    @contextmanager
    def read(self) -> Iterator[DbSession]:
        """A read transaction (it may write, but on SQLite a write may then fail busy)."""
        with self._reader() as s, s.begin():
            yield s

    @contextmanager
    def write(self) -> Iterator[DbSession]:
        """A write transaction, holding the database's one write lock from its start
        (SQLite's, or the PostgreSQL advisory lock `WRITE_LOCK`) until it ends."""
        with (
            self._write_lock or nullcontext(),
            self._writer() as s,
            s.begin(),
        ):
            if not self.is_sqlite:
                s.execute(_TAKE_WRITE_LOCK)
            yield s

    def dispose(self) -> None:
        """Close every pooled connection."""
        self.read_engine.dispose()
        if self.write_engine is not self.read_engine:
            self.write_engine.dispose()


def add_missing_columns(bind: Engine | Connection) -> list[str]:
    """Add the model's nullable columns missing from existing tables; "table.column" of each.

    A column added by a later version (``rounds.shown_at``) is nullable, so an older
    database gains it with a portable ``ALTER TABLE … ADD COLUMN`` and keeps its rows.
    `bind`: an engine (its own transaction) or a connection (the caller's transaction).
    Raises RuntimeError for a missing column that is not nullable (that needs a migration).
    """
    added: list[str] = []
    with bind.begin() if isinstance(bind, Engine) else nullcontext(bind) as connection:
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
                kind = column.type.compile(dialect=connection.dialect)
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
