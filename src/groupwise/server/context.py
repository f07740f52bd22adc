"""What every request handler can reach: one `AppContext` per app, made by `create_app`."""

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from threading import Lock

from groupwise.clips.store import ClipStore
from groupwise.server.config import AppConfig
from groupwise.server.schemas.rounds import TreeNodeOut
from groupwise.storage import Database
from groupwise.storage.annotators import OWNER_CALLER, Caller, by_token
from groupwise.storage.team import ScoreSource, pool_scores
from groupwise.worker.supervisor import Supervisor, WorkerConfig

CLIPS_DIR = "clips"
"""The clip store's folder in the data directory, shared by all sessions."""


@dataclass(frozen=True)
class Viewer:
    """Whom a session's state is for (its ``me``) and where the reward model's predicted
    returns come from (its annotators' model agreement; None: not computed)."""

    caller: Caller = OWNER_CALLER
    scores: ScoreSource | None = None


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
    scores: dict[tuple[str, int], Mapping[str, float]] = field(default_factory=dict)
    """(session, round) → the predicted returns its pool stores (`team.pool_scores`)."""

    def identify(self, token: str) -> Caller | None:
        """The present annotator whose token `token` is, or None (`GuardMiddleware`)."""
        with self.db.read() as s:
            return by_token(s, token)

    def round_scores(
        self, session_id: str, round_index: int, pool_dir: str | None
    ) -> Mapping[str, float] | None:
        """The predicted returns of a round's pool, read once (a pool never changes)."""
        key = (session_id, round_index)
        with self.trees_lock:
            cached = self.scores.get(key)
        if cached is not None:
            return cached
        found = pool_scores(self.data_dir, pool_dir)
        if found is not None:
            with self.trees_lock:
                self.scores[key] = found
        return found

    def viewer(self, caller: Caller = OWNER_CALLER) -> Viewer:
        """The state as `caller` sees it, with the model agreement from the pools."""
        return Viewer(caller, self.round_scores)

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
                    processes=config.training_workers,
                ),
            ),
        )
