"""What every request handler can reach: one `AppContext` per app, made by `create_app`."""

from dataclasses import dataclass, field
from pathlib import Path
from threading import Lock

from groupwise.clips.store import ClipStore
from groupwise.server.config import AppConfig
from groupwise.server.schemas import TreeNodeOut
from groupwise.storage import Database
from groupwise.worker.supervisor import Supervisor, WorkerConfig

CLIPS_DIR = "clips"
"""The clip store's folder in the data directory, shared by all sessions."""


@dataclass
class AppContext:
    """The app's database, clip store, worker supervisor and read caches."""

    config: AppConfig
    db: Database
    clips: ClipStore
    supervisor: Supervisor
    trees: dict[tuple[str, int], tuple[TreeNodeOut, int, dict[str, list[str]]]] = field(
        default_factory=dict
    )
    """(session, round) → (tree, levels, medoids): a prepared pool never changes."""
    trees_lock: Lock = field(default_factory=Lock)

    @property
    def data_dir(self) -> Path:
        return self.config.data_dir

    @classmethod
    def open(cls, config: AppConfig) -> "AppContext":
        """Open the database (creating its tables) and the clip store of `config`."""
        config.data_dir.mkdir(parents=True, exist_ok=True)
        db = Database(config.db_url)
        db.create_schema()
        return cls(
            config=config,
            db=db,
            clips=ClipStore(config.data_dir / CLIPS_DIR),
            supervisor=Supervisor(
                db,
                WorkerConfig(
                    config.db_url,
                    config.data_dir,
                    worker_poll_s=config.worker_poll_s,
                    supervisor_poll_s=config.supervisor_poll_s,
                ),
            ),
        )
