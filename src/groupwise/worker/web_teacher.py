"""A person as the teacher of a user's own loop, through the running app's web page.

`WebTeacher` is a `groupwise.teachers.Teacher`: `answer(pool, queries, rng)` publishes the
pool as the next round of a session of the app (clips, behaviour tree, the strategy's
queries as the page's suggestions), then blocks until the person ends the round on the page
(or the round's comparison limit or time is reached), and returns the person's judgements.
The app's own training worker leaves such a session alone (``driver: "library"``): the
user's program trains between rounds, and the page shows "waiting for your program".

It talks to the app through the app's data directory and database (the same machine, e.g.
``groupwise serve --data DIR`` beside the program), exactly as the app's worker does:

    teacher = WebTeacher("data", env="Pendulum-v1")     # `groupwise serve --data data`
    loop = PreferenceComparisons(make, agent, reward, Feedback(GroupSuggestions(), teacher))
    loop.train()
    teacher.close()                                     # the session shows as finished
"""

import logging
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.clips.render import RenderPool
from groupwise.preferences.judgement import Judgement
from groupwise.query.strategies import Query
from groupwise.storage import Database, SessionSettings, default_url
from groupwise.storage.judgements import round_judgements
from groupwise.storage.lifecycle import finish_session, finish_training
from groupwise.storage.phases import FAILED, FINISHED, PREPARING, READY, TRAINING
from groupwise.storage.progress import set_progress
from groupwise.storage.sessions import create_session, get_session
from groupwise.storage.settings import LIBRARY
from groupwise.worker.publishing import publish_offer, published_round

log = logging.getLogger(__name__)

MAX_ROUNDS = next(m.le for m in SessionSettings.model_fields["rounds"].metadata if hasattr(m, "le"))
"""Rounds of a session whose `settings` name none (the most a session may have): the
program, not the app, decides when it ends (`close`)."""


class SessionGoneError(RuntimeError):
    """The person's session ended (finished or failed) while the program waited for it."""


class WebTeacher:
    """Answers each round's queries by a person on the app's page (module docstring).

    `data_dir` is the app's data directory (its SQLite database unless `database_url` is
    given); `env` the env id the page renders clips of (a groupwise env name, a Gymnasium id
    or ``module:Env-v0``: the env the program's pool came from); `mode` "groupwise" or
    "pairwise"; `settings` the session's settings (pool size, comparisons per round, round
    time, clip size, ...; the driver is always "library"; `rounds` only sets what the page
    shows as the total). `session_id` continues a session
    this program opened before. `poll_s` is how often the database is read while waiting.
    """

    def __init__(
        self,
        data_dir: str | Path,
        env: str,
        mode: str = "groupwise",
        settings: SessionSettings | dict[str, Any] | None = None,
        *,
        session_id: str | None = None,
        database_url: str | None = None,
        annotator: str = "",
        poll_s: float = 0.5,
    ) -> None:
        self.data_dir = Path(data_dir)
        self.env = env
        self.mode = mode
        values = settings.model_dump() if isinstance(settings, SessionSettings) else settings
        values = {"rounds": MAX_ROUNDS, **(values or {}), "driver": LIBRARY}
        self.settings = SessionSettings.model_validate(values)
        self.db = Database(database_url or default_url(self.data_dir))
        self.annotator = annotator
        self.poll_s = poll_s
        self.session_id = session_id
        self._render: RenderPool | None = None

    @property
    def url_path(self) -> str:
        """The page of this teacher's session, relative to the app's address."""
        return f"/?session={self.session_id}" if self.session_id else "/"

    def answer(
        self, pool: BehaviourPool, queries: Sequence[Query], rng: np.random.Generator
    ) -> list[Judgement]:
        """Publish `pool` as round `pool.round`, wait for the person to end it, and return
        the round's judgements (not undone), in the order given.

        Raises:
            SessionGoneError: the session was finished or failed meanwhile.
            ValueError: `pool.round` is not the session's next round.
        """
        sid = self._session_for(pool.round)
        self._render = self._render or RenderPool(self.settings.render_workers)
        prepared = published_round(
            self.data_dir, sid, self.env, self.settings, pool, queries, self._render
        )
        opened = publish_offer(self.db, sid, pool.round, prepared)
        if not opened:
            raise SessionGoneError(f"session {sid} moved on while round {pool.round} was published")
        log.info("round %d is open for judgements: %s", pool.round, self.url_path)
        self._wait_until_closed(sid, pool.round)
        with self.db.write() as s:
            set_progress(s, sid, TRAINING, "training", 0.0, "waiting for your program to train")
        with self.db.read() as s:
            return [judgement for _, judgement in round_judgements(s, sid, pool.round)]

    def close(self) -> None:
        """The program is done: the session shows as finished; render workers stop."""
        if self._render is not None:
            self._render.close()
            self._render = None
        if self.session_id is None:
            return
        with self.db.write() as s:
            if get_session(s, self.session_id).phase not in (FINISHED, FAILED):
                finish_session(s, self.session_id)
        self.db.dispose()

    def __enter__(self) -> "WebTeacher":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------------------------

    def _session_for(self, round_index: int) -> str:
        """The session, waiting to be given round `round_index` (created for round 0)."""
        if self.session_id is None:
            if round_index != 0:
                raise ValueError(f"a new session starts at round 0, not {round_index}")
            with self.db.write() as s:
                sid = create_session(s, self.env, self.mode, self.settings, self.annotator).id
            self.session_id = sid  # published once committed, so others can read it
            return sid
        with self.db.write() as s:
            session = get_session(s, self.session_id, lock=True)
            if session.phase in (FINISHED, FAILED):
                raise SessionGoneError(f"session {session.id} is {session.phase}")
            if session.phase != PREPARING:  # the previous round was answered and trained
                finish_training(s, session.id, session.round, "", {})
            if session.round != round_index or session.phase != PREPARING:
                raise ValueError(
                    f"session {session.id} expects round {session.round}, got {round_index}"
                )
            return session.id

    def _wait_until_closed(self, session_id: str, round_index: int) -> None:
        while True:
            with self.db.read() as s:
                session = get_session(s, session_id)
                phase, current = session.phase, session.round
            if phase in (FINISHED, FAILED):
                raise SessionGoneError(f"session {session_id} is {phase}")
            if current != round_index or phase != READY:
                return
            time.sleep(self.poll_s)
