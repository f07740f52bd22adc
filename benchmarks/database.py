"""The database a benchmark's ``groupwise serve`` runs on: ``--db sqlite|postgresql|URL``."""

from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def database(db: str) -> Iterator[tuple[str | None, str]]:
    """(URL for ``--db``, description): SQLite in the data directory (None), a throw-away
    PostgreSQL cluster for "postgresql" (tests/postgres.py, fsync on, deleted on exit), or
    the URL given (an empty database: the benchmarks resume any unfinished session in it)."""
    if db == "sqlite":
        yield None, "SQLite in WAL mode"
    elif db == "postgresql":
        from tests.postgres import running_cluster

        with running_cluster(durable=True) as cluster:
            yield cluster.create_database(), "a local PostgreSQL over its unix socket"
    else:
        from sqlalchemy.engine import make_url

        backend = make_url(db).get_backend_name()
        yield db, {"sqlite": "SQLite", "postgresql": "PostgreSQL"}.get(backend, backend)
