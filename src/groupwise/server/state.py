"""Sessions as the page sees them: `SessionState`, creation, and the lifecycle actions.

Every read checks the round timer lazily: a round whose time budget is used up is closed
(phase ``training``) before its state is returned, so the page never sees an open round
that should have ended (the supervisor also checks, for sessions nobody is looking at).

A state is someone's (`Viewer`): its ``me`` is the caller, and its ``annotators`` the
session's team with their counters and agreement (`storage.team`, docs/teams.md).
"""

from collections.abc import Mapping, Sequence
from datetime import datetime

import gymnasium as gym
import numpy as np
from sqlalchemy.orm import Session as DbSession

from groupwise.envs import horizon, make_env
from groupwise.envs.datasets import check_dataset_env, open_dataset
from groupwise.envs.episodes import check_episode_length
from groupwise.server.context import AppContext, Viewer
from groupwise.server.schemas.annotators import AgreementOut, AnnotatorOut, MeOut, ModelAgreementOut
from groupwise.server.schemas.judgements import AnnotatorRef, JudgementOut, PairOut
from groupwise.server.schemas.sessions import Counts as CountsOut
from groupwise.server.schemas.sessions import Progress, SessionCreate, SessionState, Timer
from groupwise.storage import Database, InvalidError, lifecycle, sessions, timer
from groupwise.storage.annotators import OWNER, Caller, owner_name, record_view
from groupwise.storage.counts import Counts, counts
from groupwise.storage.judgements import JudgementRecord
from groupwise.storage.models import SessionRow, utcnow
from groupwise.storage.settings import SessionSettings
from groupwise.storage.team import AnnotatorStats, team_stats


def annotator_out(stats: AnnotatorStats) -> AnnotatorOut:
    """A team member's row as the page shows it."""
    return AnnotatorOut(
        id=stats.id,
        name=stats.name,
        comparisons=stats.comparisons,
        pairs=stats.pairs,
        shown_s=stats.shown_s,
        agreement=AgreementOut(
            kappa=stats.agreement.kappa, share=stats.agreement.share, n=stats.agreement.n
        ),
        model_agreement=ModelAgreementOut(
            share=stats.model_agreement.share, n=stats.model_agreement.n
        ),
    )


def me_of(session: SessionRow, caller: Caller) -> MeOut:
    """Who `caller` is in `session`."""
    name = owner_name(session) if caller.is_owner else caller.name
    return MeOut(id=caller.id, name=name, owner=caller.is_owner)


def state_of(
    session: SessionRow,
    counted: Counts,
    now: datetime,
    shown_at: datetime | None = None,
    *,
    me: MeOut | None = None,
    team: Sequence[AnnotatorStats] = (),
) -> SessionState:
    """The `SessionState` of a session row (`shown_at`: its current round's; `me`: the
    caller, default the owner; `team`: `storage.team.team_stats`)."""
    settings = SessionSettings.stored(session.settings)
    return SessionState(
        id=session.id,
        env=session.env,
        mode=session.mode,  # type: ignore[arg-type]  # one of MODES, checked on creation
        settings=settings,
        annotator=session.annotator,
        round=session.round,
        rounds=settings.rounds,
        phase=session.phase,  # type: ignore[arg-type]  # one of PHASES
        progress=Progress(
            phase=session.progress_phase,
            fraction=session.progress_fraction,
            message=session.progress_message,
        ),
        error=session.error,
        failed_phase=session.failed_phase if session.phase == "failed" else None,  # type: ignore[arg-type]  # one of WORK_PHASES
        timer=Timer(
            elapsed_s=round(timer.elapsed(session, now), 3),
            budget_s=settings.round_seconds,
            paused=session.paused,
            running=session.timer_started_at is not None,
            shown_at=shown_at,
        ),
        counts=CountsOut(
            comparisons_round=counted.comparisons_round,
            pairs_round=counted.pairs_round,
            comparisons_total=counted.comparisons_total,
            pairs_total=counted.pairs_total,
        ),
        created_at=session.created_at,
        origin=session.origin,
        me=me or MeOut(id=OWNER, name=owner_name(session), owner=True),
        annotators=[annotator_out(stats) for stats in team],
    )


def close_if_due(db: Database, session_id: str) -> int:
    """Close the session's round if its time is up; the session's revision after that.

    Raises NotFoundError.
    """
    with db.read() as s:
        session = sessions.get_session(s, session_id)
        if not timer.round_due(session):
            return session.revision
    with db.write() as s:
        lifecycle.close_if_due(s, session_id)
        return sessions.get_session(s, session_id).revision


def _state(s: DbSession, session: SessionRow, now: datetime, viewer: Viewer) -> SessionState:
    return state_of(
        session,
        counts(s, session),
        now,
        timer.shown_at(s, session),
        me=me_of(session, viewer.caller),
        team=team_stats(s, session, now, viewer.scores),
    )


def read_state(db: Database, session_id: str, viewer: Viewer | None = None) -> SessionState:
    """The session's current state as `viewer` sees it (default: the owner, without the
    model agreement). Raises NotFoundError."""
    close_if_due(db, session_id)
    with db.read() as s:
        return _state(s, sessions.get_session(s, session_id), utcnow(), viewer or Viewer())


def list_states(db: Database, viewer: Viewer | None = None) -> list[SessionState]:
    """Every session's state, newest first; an annotator's own session only."""
    viewer = viewer or Viewer()
    now = utcnow()
    mine = viewer.caller.session_id
    with db.read() as s:
        rows = sessions.list_sessions(s)
        return [_state(s, row, now, viewer) for row in rows if mine is None or row.id == mine]


def check_env(env: str, settings: SessionSettings) -> SessionSettings:
    """The settings a new session of `env` stores (`SessionSettings.for_env`: its L in
    steps). Raises InvalidError unless `env` is known, can be made here, its horizon holds a
    behaviour, a random policy's episodes last long enough to hold one
    (`envs.episodes.check_episode_length`), and its actions are a Box when pre-training
    hands over at an action noise (`teach_log_std`)."""
    try:
        steps = horizon(env)
        resolved = settings.for_env(env)  # makes the env once, for its step duration
    except ValueError as error:
        raise InvalidError(str(error)) from None
    except Exception as error:
        # A registered id runs its own constructor, which fails its own way (e.g. Gymnasium's
        # DependencyNotInstalled for CarRacing-v3 without Box2D): the id is the person's error.
        raise InvalidError(f"env {env!r} cannot be made here: {error}") from None
    # a recipe sets the noise only on MuJoCo envs (Box actions): check only one set by hand
    if settings.teach_log_std is not None and resolved.recipe_parts(env).pretrain_steps > 0:
        probe = make_env(env)
        try:
            actions = probe.action_space
        finally:
            probe.close()
        if not isinstance(actions, gym.spaces.Box):
            raise InvalidError(
                f"teach_log_std sets a Gaussian action noise, and env {env} has {actions} "
                "actions: leave it empty"
            )
    length = resolved.fragment_length
    seconds = resolved.clip_timing(env).seconds
    if steps is None or length is None or steps < length:
        raise InvalidError(
            f"env {env} needs a fixed horizon of at least fragment_length = {length} steps "
            f"({seconds:.3g} s); it has {steps}"
        )
    try:  # an env that ends episodes early (issue 23): round 0 would fail, and every retry
        window = f" (clip_seconds = {seconds:.3g} s)"
        check_episode_length(env, length, np.random.default_rng(resolved.seed), window)
    except ValueError as error:
        raise InvalidError(str(error)) from None
    return resolved


MIN_DATASET_WINDOWS = 2
"""Fewest windows a dataset session's episodes must hold (a comparison needs two)."""


def check_new_session(env: str | None, settings: SessionSettings) -> tuple[str, SessionSettings]:
    """The env and settings a new session stores: `check_env`'s, or for a session over a
    recorded dataset (`settings.dataset`) `check_dataset`'s. Raises InvalidError."""
    if settings.dataset is not None:
        return check_dataset(settings.dataset, env, settings)
    if env is None:
        raise InvalidError("env is required unless settings.dataset names a recorded dataset")
    return env, check_env(env, settings)


def check_dataset(
    reference: str, env: str | None, settings: SessionSettings
) -> tuple[str, SessionSettings]:
    """The env (`env`, else the one the dataset names) and settings (the dataset's reference
    made absolute, L in steps) of a new session labelling the recorded dataset `reference`
    (`envs.datasets.open_dataset`). Raises InvalidError unless the dataset can be read, the
    env made and its clips drawn (`check_dataset_env`), and its episodes hold at least
    `MIN_DATASET_WINDOWS` windows of L steps."""
    try:
        dataset = open_dataset(reference)
    except ValueError as error:
        raise InvalidError(str(error)) from None
    name = env or dataset.env
    if name is None:
        raise InvalidError(f"dataset {reference} names no env: give the env to show it in")
    try:
        resolved = settings.model_copy(update={"dataset": dataset.reference}).for_env(name)
        probe = make_env(name)
        try:
            check_dataset_env(dataset, probe, name)
        finally:
            probe.close()
    except ValueError as error:
        raise InvalidError(str(error)) from None
    except Exception as error:  # as in check_env: the env's own constructor failed
        raise InvalidError(f"env {name!r} cannot be made here: {error}") from None
    length = resolved.fragment_length or 0
    held = sum(len(e) // length for e in dataset.episodes)
    if held < MIN_DATASET_WINDOWS:
        seconds = resolved.clip_timing(name).seconds
        raise InvalidError(
            f"dataset {reference}'s episodes hold {held} windows of {length} steps "
            f"({seconds:.3g} s of {name}); it needs {MIN_DATASET_WINDOWS}: ask for shorter "
            "clips (clip_seconds or fragment_length)"
        )
    return name, resolved


def create_session(context: AppContext, request: SessionCreate) -> SessionState:
    """Create a session (its round 0 is queued for the worker). Raises InvalidError."""
    env, settings = check_new_session(request.env, request.settings)
    with context.db.write() as s:
        session = sessions.create_session(s, env, request.mode, settings, request.annotator)
        session_id = session.id
    context.supervisor.ensure_worker_soon()
    return read_state(context.db, session_id, context.viewer())


def pause(context: AppContext, session_id: str) -> SessionState:
    with context.db.write() as s:
        timer.pause(s, session_id)
    return read_state(context.db, session_id, context.viewer())


def show_round(
    context: AppContext, session_id: str, round_index: int, caller: Caller
) -> SessionState:
    """`caller`'s page shows the open round: the round's timer starts the first time
    anyone shows it, and the caller's time shown the first time they do. Raises
    NotFoundError, ConflictError."""
    with context.db.write() as s:
        timer.show_round(s, session_id, round_index)
        record_view(s, session_id, round_index, caller)
    return read_state(context.db, session_id, context.viewer(caller))


def resume(context: AppContext, session_id: str) -> SessionState:
    with context.db.write() as s:
        timer.resume(s, session_id)
    return read_state(context.db, session_id, context.viewer())


def close_open_round(context: AppContext, session_id: str) -> SessionState:
    with context.db.write() as s:
        lifecycle.close_open_round(s, session_id)
    context.supervisor.ensure_worker_soon()
    return read_state(context.db, session_id, context.viewer())


def retry(context: AppContext, session_id: str) -> SessionState:
    """Re-queue the failed step and make sure a worker runs. Raises ConflictError."""
    with context.db.write() as s:
        lifecycle.retry(s, session_id)
    context.supervisor.ensure_worker_soon()
    return read_state(context.db, session_id, context.viewer())


def judgement_out(record: JudgementRecord, names: Mapping[str, str]) -> JudgementOut:
    """The page's view of a stored judgement; `names`: id → name of the session's people
    (`storage.annotators.display_names`)."""
    if record.annotator_id == OWNER:  # the owner's own name for it, if they gave one
        name = record.annotator or names.get(OWNER, OWNER)
    else:
        name = names.get(record.annotator_id, record.annotator or record.annotator_id)
    return JudgementOut(
        id=record.id,
        client_id=record.client_id,
        round=record.round,
        left=list(record.left),
        right=list(record.right),
        label=record.label,  # type: ignore[arg-type]  # validated on storing
        source=record.source,
        seconds=record.seconds,
        edits=record.edits,
        annotator=AnnotatorRef(id=record.annotator_id, name=name),
        suggestion_id=record.suggestion_id,
        created_at=record.created_at,
        undone=record.undone,
        pairs=[PairOut(a=p.a, b=p.b, label=p.label) for p in record.pairs],
    )
