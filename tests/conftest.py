"""Settings every test process shares, and the database every storage test runs on.

`db_backend` is "sqlite" here; tests/unit/storage and tests/unit/server override it with
both backends, so their tests run on SQLite and on PostgreSQL (a throw-away cluster of
Debian's server per test process, `tests/postgres.py`, a database per test). Without
PostgreSQL installed the PostgreSQL cases skip, or fail when ``GROUPWISE_PG_REQUIRED=1``
(`make test` sets it, as ``GROUPWISE_E2E_REQUIRED`` for the browser tests).
"""

import multiprocessing
import os
from collections.abc import Iterator
from pathlib import Path

import pytest
import torch
from tests.postgres import PostgresCluster, find_bin_dir

# Tiny nets: torch's intra-op threads only contend with pytest-xdist's other worker (see cli.py).
torch.set_num_threads(1)


@pytest.fixture(autouse=True)
def _children_end_with_their_test() -> Iterator[None]:
    """Processes a test started and left (a dropped `Worker`'s curve evaluator, ~390 MB,
    lives until the garbage collector gets to it) end with the test; those of wider-scoped
    fixtures, started before it, are left alone."""
    before = set(multiprocessing.active_children())
    yield
    for child in set(multiprocessing.active_children()) - before:
        child.terminate()
        child.join(5)


@pytest.fixture(scope="session")
def db_backend() -> str:
    """The database the app's tests use (overridden with both by storage and server tests)."""
    return "sqlite"


@pytest.fixture(scope="session")
def postgres_cluster() -> Iterator[PostgresCluster]:
    """One PostgreSQL server for this test process (each xdist worker starts its own)."""
    bin_dir = find_bin_dir()
    if bin_dir is None:
        message = (
            "PostgreSQL's server is not installed (Debian: apt-get install postgresql, or "
            "GROUPWISE_PG_BIN=<dir of initdb>)"
        )
        if os.environ.get("GROUPWISE_PG_REQUIRED") == "1":
            pytest.fail(message)
        pytest.skip(message)
    cluster = PostgresCluster(bin_dir)
    try:
        yield cluster.start()
    finally:
        cluster.stop()


def new_database_url(request: pytest.FixtureRequest, backend: str, directory: Path) -> str:
    """A new, empty database of `backend`: a SQLite file in `directory`, or a database of
    this process's PostgreSQL cluster (dropped when `request`'s scope ends)."""
    if backend == "sqlite":
        from groupwise.storage import default_url

        return default_url(directory)
    cluster: PostgresCluster = request.getfixturevalue("postgres_cluster")
    url = cluster.create_database()
    request.addfinalizer(lambda: cluster.drop_database(url))
    return url


@pytest.fixture
def database_url(request: pytest.FixtureRequest, db_backend: str, tmp_path: Path) -> str:
    """A new, empty database of the test's backend."""
    return new_database_url(request, db_backend, tmp_path)
