"""A worker job as the worker finds it in the database, and the session's run it works on.

A `Job` is one step of one session (`job_of`: its phase, round and settings); `open_run` is
the session's `Run` in ``DIR/sessions/<session>/`` as a round left it, `checkpoint_of` and
`committed_record` where a round's training went; `session_strategy` and `offered_queries`
what a round of the session offers its person.
"""

import json
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

from groupwise.agent_file.summary import SETTINGS_FILE
from groupwise.config import RunConfig
from groupwise.query.strategies import QueryStrategy
from groupwise.run.checkpoint import CHECKPOINTS, STATE_FILE, checkpoint_dir
from groupwise.run.pretrain import before_first_round
from groupwise.run.records import RoundRecord, read_record
from groupwise.run.run import Run
from groupwise.storage import Database, SessionSettings
from groupwise.storage.phases import WORK_PHASES
from groupwise.storage.sessions import get_round, get_session, session_directory, settings_of
from groupwise.storage.timer import elapsed
from groupwise.teachers import STRATEGIES

QUEUE_FACTOR = 2
"""A round offers this many times its comparison budget in queries (skips use some up)."""


@dataclass(frozen=True)
class Job:
    """One step of one session, as the worker found it in the database."""

    session_id: str
    env: str
    mode: str  # "groupwise" or "pairwise"
    phase: str  # "preparing", "training" or "finishing"
    round: int
    settings: SessionSettings
    elapsed_s: float  # the round's timer when training started (for the round record)
    frozen_steps: int | None = None
    """PPO steps of the current round when it is one without feedback (`RoundRow`)."""


def job_of(db: Database, session_id: str) -> Job | None:
    """The job a session waits for, or None when it waits for none."""
    with db.read() as s:
        session = get_session(s, session_id)
        if session.phase not in WORK_PHASES:
            return None
        return Job(
            session_id=session.id,
            env=session.env,
            mode=session.mode,
            phase=session.phase,
            round=session.round,
            settings=settings_of(session),
            elapsed_s=elapsed(session),
            frozen_steps=get_round(s, session.id, session.round).frozen_steps,
        )


def open_run(job: Job, data_dir: Path, after: int) -> Run:
    """The session's run as round `after` left it (fresh for −1: after its setup hooks,
    `run.pretrain.before_first_round`, as a headless run begins, run once per session:
    `_set_up`); writes its
    ``config.json`` and ``settings.json`` (the settings may have changed since: "Finish
    now", "Continue training")."""
    cfg = job.settings.run_config(job.env)
    out = data_dir / session_directory(job.session_id)
    run = Run.create(cfg, out)
    (out / SETTINGS_FILE).write_text(job.settings.model_dump_json(indent=2) + "\n")
    if not run.restore(after):
        _set_up(run)
    return run


PRETRAINED = "pretrained"
"""``checkpoints/pretrained`` of a session: its agent as its setup hooks left it, before
round 0 (`open_run`)."""


def _set_up(run: Run) -> None:
    """Run a fresh session run's setup hooks once (`run.pretrain.before_first_round`): the
    first open (the job preparing round 0) runs them and writes the agent they leave to
    ``checkpoints/pretrained``; every later open of the fresh run (the job ending round 0,
    round 0's continuous training, a restarted worker) loads that instead of pre-training
    again (issue 39: the app pre-trained twice for round 0)."""
    directory = run.directory / CHECKPOINTS / PRETRAINED
    if (directory / STATE_FILE).is_file():
        run.load_policy(directory)
        return
    if not before_first_round(run) or run.agent.num_timesteps == 0:
        return  # no hook trained the agent: nothing to keep
    tmp = directory.with_name(directory.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    run.save_policy(tmp)
    (tmp / STATE_FILE).write_text(json.dumps({"env_steps": run.agent.num_timesteps}))
    shutil.rmtree(directory, ignore_errors=True)
    os.replace(tmp, directory)


def session_strategy(cfg: RunConfig, mode: str) -> QueryStrategy:
    """What the page suggests: the Pairwise-DM's queries in pairwise mode, else the
    Groupwise-DM's group suggestions (`groupwise.teachers.STRATEGIES`)."""
    return STRATEGIES["pairwise" if mode == "pairwise" else "groupwise"](cfg)


def offered_queries(settings: SessionSettings) -> int:
    """How many queries a round offers: `QUEUE_FACTOR` × its budget (× its pool when it
    has no limit)."""
    return QUEUE_FACTOR * (settings.comparisons_per_round or settings.pool_size)


def checkpoint_of(session_id: str, round_index: int) -> str:
    """The checkpoint directory of a session's round, relative to the data directory."""
    return str(checkpoint_dir(Path(session_directory(session_id)), round_index))


def committed_record(data_dir: Path, session_id: str, round_index: int) -> RoundRecord | None:
    """The record of round `round_index` from its checkpoint on disk, when `end_round`
    wrote it (None when it did not: the round is still to be committed)."""
    state = data_dir / checkpoint_of(session_id, round_index) / STATE_FILE
    try:
        row = json.loads(state.read_text())["records"][-1]
    except (OSError, ValueError, KeyError, IndexError):
        return None
    return read_record(row) if row.get("round") == round_index else None
