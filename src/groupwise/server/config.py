"""The configuration of one app instance (`create_app`), set by `groupwise serve` or a test."""

from dataclasses import dataclass
from pathlib import Path

import groupwise
from groupwise.storage import default_url

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
"""Host header names accepted by a loopback server (anything else is DNS rebinding)."""
MAX_BODY_BYTES = 1 << 20
"""Request bodies above this are refused with 413 (docs/app.md, "Security")."""


def default_static_dir() -> Path:
    """The web UI inside the package, ``groupwise/static/`` (package data; in a checkout
    ``src/groupwise/static/``, written by ``cd web && npm run build`` or ``make``)."""
    return Path(groupwise.__file__).resolve().parent / "static"


@dataclass(frozen=True)
class AppConfig:
    """Where the app keeps its data and how it guards and paces itself."""

    data_dir: Path
    """The data directory: database (by default), clip store, pools, checkpoints."""
    database_url: str | None = None
    """A SQLAlchemy URL; None means SQLite at ``data_dir/groupwise.db``."""
    token: str | None = None
    """When set, every /api and /clips request must carry it (Bearer header or ?token=)."""
    allowed_hosts: tuple[str, ...] | None = LOOPBACK_HOSTS
    """Host header names accepted (None: any). A loopback server accepts only loopback
    names, so a web page elsewhere cannot reach it through DNS rebinding."""
    static_dir: Path | None = None
    """The built web UI (``index.html`` and assets); None means `default_static_dir()`."""
    start_worker: bool = True
    """Run and supervise the training worker process (off for schema-only tests)."""
    max_body_bytes: int = MAX_BODY_BYTES
    """Largest request body accepted."""
    events_poll_s: float = 0.25
    """How often an event stream polls the database for changes."""
    keepalive_s: float = 15.0
    """Seconds between keep-alive comments of a quiet event stream."""
    supervisor_poll_s: float = 0.25
    """How often the supervisor checks the worker and the round timers."""
    worker_poll_s: float = 0.25
    """How often an idle worker polls the database for work."""
    training_workers: int = 1
    """Training worker processes (``serve --training-workers``); each serves a share of the
    sessions (`worker.process.shard_of`), so on a lab server several sessions train on
    different cores. One on a 2-core machine: PPO has one core, the server the other."""
    clip_workers: int = 2
    """Processes of the server that render clips on demand (`clips.on_demand`)."""
    ray_address: str | None = None
    """Render clips on demand as tasks on this Ray cluster instead (``serve --ray``), as many
    at a time as it has CPUs."""

    @property
    def db_url(self) -> str:
        return self.database_url or default_url(self.data_dir)

    @property
    def static_root(self) -> Path:
        return self.static_dir or default_static_dir()
