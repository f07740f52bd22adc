"""A throw-away PostgreSQL cluster for tests and benchmarks: Debian's server, no mocks.

`PostgresCluster.start()` runs ``initdb`` into a fresh temporary directory (trust
authentication, one superuser ``postgres``) and starts ``postgres`` on it, listening only on
a unix socket in that directory (``listen_addresses=''``) under a free port number, so
clusters of several pytest-xdist workers never meet. `create_database()` gives each test a
database of its own; `stop()` shuts the server down (fast shutdown) and deletes everything.

initdb and postgres refuse to run as root, and CI and the dev machines run as root: then
both run as the unprivileged user ``nobody`` (`subprocess`'s ``user=``/``group=``, no
helper program), and the cluster directory is made theirs. The test process, root, can use
the socket anyway.

The server programs are found in ``$GROUPWISE_PG_BIN`` when it is set (only there), else in
Debian's ``/usr/lib/postgresql/<version>/bin`` (newest version first; scripts/system-deps.sh
installs the ``postgresql`` package), else on PATH.
"""

import contextlib
import os
import pwd
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

BACKENDS = ("sqlite", "postgresql")
"""The databases the storage and server tests run on (tests/conftest.py)."""
UNPRIVILEGED = "nobody"
"""The user initdb and postgres run as when the tests run as root."""
START_TIMEOUT_S = 60.0

SETTINGS = {"listen_addresses": "", "max_connections": "200", "shared_buffers": "32MB"}
FAST = {"fsync": "off", "full_page_writes": "off"}
"""A test cluster need not survive a power cut (`durable=False`); the storage code commits
as it would. A benchmark keeps both on, as SQLite's ``synchronous=FULL``."""


def find_bin_dir() -> Path | None:
    """The directory holding ``initdb`` and ``postgres``, or None (module docstring)."""
    if os.environ.get("GROUPWISE_PG_BIN"):  # that one alone (a wrong one: not installed)
        candidates = [Path(os.environ["GROUPWISE_PG_BIN"])]
    else:
        candidates = _installed()
    for directory in candidates:
        if (directory / "initdb").is_file() and (directory / "postgres").is_file():
            return directory
    return None


def _installed() -> list[Path]:
    debian = sorted(
        Path("/usr/lib/postgresql").glob("*/bin"),
        key=lambda p: [int(x) if x.isdigit() else 0 for x in p.parent.name.split(".")],
        reverse=True,
    )
    on_path = shutil.which("initdb")
    return [*debian, *([Path(on_path).resolve().parent] if on_path else [])]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class PostgresCluster:
    """One PostgreSQL server on a temporary cluster; `url()` of its databases."""

    def __init__(self, bin_dir: Path, *, durable: bool = False) -> None:
        self.bin_dir = bin_dir
        self.settings = SETTINGS if durable else {**SETTINGS, **FAST}
        self.root = Path(tempfile.mkdtemp(prefix="groupwise-pg-"))
        self.data = self.root / "data"
        self.port = free_port()
        self.process: subprocess.Popen[bytes] | None = None
        self._as: dict[str, object] = {}
        if os.geteuid() == 0:
            user = pwd.getpwnam(UNPRIVILEGED)
            os.chown(self.root, user.pw_uid, user.pw_gid)
            self._as = {"user": user.pw_uid, "group": user.pw_gid, "extra_groups": []}

    @property
    def socket_dir(self) -> Path:
        return self.root

    def url(self, database: str = "postgres") -> str:
        """The SQLAlchemy URL of `database` (psycopg 3, over the unix socket)."""
        return f"postgresql+psycopg://postgres@/{database}?host={self.socket_dir}&port={self.port}"

    def start(self) -> "PostgresCluster":
        """initdb and start the server; returns once it accepts connections.

        Raises RuntimeError with the server's log when it does not start.
        """
        subprocess.run(
            [
                str(self.bin_dir / "initdb"),
                "-D", str(self.data), "-U", "postgres", "-A", "trust",
                "-E", "UTF8", "--locale=C.UTF-8", "--no-sync",
            ],
            check=True,
            capture_output=True,
            cwd=self.root,
            **self._as,  # type: ignore[arg-type]  # user/group keywords  # user/group/extra_groups of Popen
        )  # fmt: skip
        options = [f"-c{key}={value}" for key, value in self.settings.items()]
        log = open(self.root / "postgres.log", "wb")  # the server's stdout, closed below
        with log:
            self.process = subprocess.Popen(
                [
                    str(self.bin_dir / "postgres"),
                    "-D", str(self.data), "-p", str(self.port),
                    "-k", str(self.socket_dir), *options,
                ],
                stdout=log,
                stderr=subprocess.STDOUT,
                cwd=self.root,
                **self._as,  # type: ignore[arg-type]  # user/group keywords
            )  # fmt: skip
        self._wait_ready()
        return self

    def _wait_ready(self) -> None:
        import psycopg

        deadline = time.monotonic() + START_TIMEOUT_S
        while True:
            assert self.process is not None
            if self.process.poll() is not None:
                raise RuntimeError(f"postgres exited at start:\n{self.log()}")
            try:
                psycopg.connect(**self._connect_args("postgres")).close()
                return
            except psycopg.OperationalError:
                if time.monotonic() > deadline:
                    raise RuntimeError(f"postgres did not start:\n{self.log()}") from None
                time.sleep(0.05)

    def _connect_args(self, database: str) -> dict[str, object]:
        return {
            "host": str(self.socket_dir),
            "port": self.port,
            "user": "postgres",
            "dbname": database,
            "autocommit": True,
        }

    def log(self) -> str:
        path = self.root / "postgres.log"
        return path.read_text(errors="replace")[-4000:] if path.is_file() else ""

    def create_database(self) -> str:
        """A new, empty database; returns its URL."""
        import psycopg

        name = f"t_{uuid.uuid4().hex[:16]}"
        with psycopg.connect(**self._connect_args("postgres")) as connection:
            connection.execute(f'CREATE DATABASE "{name}"')
        return self.url(name)

    def drop_database(self, url: str) -> None:
        """Drop a database `create_database` made, closing what is still connected to it."""
        import psycopg

        name = url.split("@/", 1)[1].split("?", 1)[0]
        with psycopg.connect(**self._connect_args("postgres")) as connection:
            connection.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')

    def stop(self) -> None:
        """Shut the server down (SIGINT: fast shutdown) and delete the cluster."""
        if self.process is not None and self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        shutil.rmtree(self.root, ignore_errors=True)


@contextlib.contextmanager
def running_cluster(*, durable: bool = False) -> Iterator[PostgresCluster]:
    """A started `PostgresCluster`, stopped on exit. Raises RuntimeError when PostgreSQL's
    server programs are not installed."""
    found = find_bin_dir()
    if found is None:
        raise RuntimeError("PostgreSQL's server programs (initdb, postgres) are not installed")
    cluster = PostgresCluster(found, durable=durable)
    try:
        yield cluster.start()
    finally:
        cluster.stop()
