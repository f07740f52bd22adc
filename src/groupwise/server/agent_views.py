"""The end of a session as the page sees it: "Finish now", "Continue training", and the
final agent (its summary, video and download; `groupwise.run.final` writes them)."""

from dataclasses import asdict
from pathlib import Path
from typing import cast

from groupwise.agent_file.summary import AGENT_VIDEO, AGENT_ZIP, AgentSummary, read_summary
from groupwise.run.agent_package import NoCheckpointError, UnknownRoundError, pick_round
from groupwise.run.checkpoint import checkpoint_dir
from groupwise.server.context import AppContext
from groupwise.server.schemas.agent import (
    AgentOut,
    AgentRound,
    AgentTarget,
    AgentVideo,
    ChosenBy,
    ContinueIn,
)
from groupwise.server.schemas.sessions import SessionState
from groupwise.server.state import read_state
from groupwise.storage import ConflictError, NotFoundError, ending
from groupwise.storage.phases import FINISHED
from groupwise.storage.sessions import get_session, session_directory


def finish_now(context: AppContext, session_id: str) -> SessionState:
    """No more rounds after the current one (`storage.ending.finish_now`). Raises
    NotFoundError, ConflictError."""
    with context.db.write() as s:
        ending.finish_now(s, session_id)
    context.supervisor.ensure_worker_soon()
    return read_state(context.db, session_id, context.viewer())


def continue_training(context: AppContext, session_id: str, request: ContinueIn) -> SessionState:
    """More PPO steps or more rounds for a finished session. Raises NotFoundError,
    ConflictError, InvalidError."""
    with context.db.write() as s:
        ending.continue_training(s, session_id, steps=request.steps, rounds=request.rounds)
    context.supervisor.ensure_worker_soon()
    return read_state(context.db, session_id, context.viewer())


def _summary(context: AppContext, session_id: str) -> tuple[AgentSummary, Path]:
    with context.db.read() as s:
        session = get_session(s, session_id)
        phase = session.phase
    if phase != FINISHED:
        raise ConflictError(
            f"session {session_id} is {phase}; its final agent is ready once it is finished"
        )
    directory = context.data_dir / session_directory(session_id)
    summary = read_summary(directory)
    if summary is None:
        raise NotFoundError(
            f"session {session_id} has no final agent (it was imported, driven by a program, "
            "or finished before the app published agents)"
        )
    return summary, directory


def agent(context: AppContext, session_id: str) -> AgentOut:
    """The finished session's agent summary. Raises NotFoundError, ConflictError."""
    summary, directory = _summary(context, session_id)
    return _agent_out(summary, directory)


def pick(context: AppContext, session_id: str, round_index: int) -> AgentOut:
    """Hand over round `round_index`'s policy (`agent_package.pick_round`). Raises
    NotFoundError (no such round), ConflictError (not finished, or no checkpoint)."""
    _, directory = _summary(context, session_id)
    try:
        summary = pick_round(directory, round_index)
    except UnknownRoundError as error:
        raise NotFoundError(f"session {session_id} has {error}") from None
    except NoCheckpointError as error:
        raise ConflictError(str(error)) from None
    return _agent_out(summary, directory)


def round_video(context: AppContext, session_id: str, round_index: int) -> Path:
    """The path of round `round_index`'s clip. Raises NotFoundError, ConflictError."""
    summary, directory = _summary(context, session_id)
    video = next((r.video for r in summary.rounds if r.round == round_index), None)
    if video is None or not (directory / video.file).is_file():
        raise NotFoundError(f"session {session_id} has no clip of round {round_index}")
    return directory / video.file


def _agent_out(summary: AgentSummary, directory: Path) -> AgentOut:
    data = asdict(summary)
    return AgentOut(
        env=summary.env,
        round=summary.round,
        env_steps=summary.env_steps,
        measure=summary.measure,
        true_return_mean=summary.true_return_mean,
        true_return_std=summary.true_return_std,
        target=None if summary.target is None else AgentTarget(**data["target"]),
        target_score_mean=summary.target_score_mean,
        target_score_std=summary.target_score_std,
        video=None if summary.video is None else AgentVideo(**data["video"]),
        rounds=[
            AgentRound(
                **{k: v for k, v in r.items() if k != "video"},
                video=r["video"] is not None,
                checkpoint=(checkpoint_dir(directory, r["round"]) / "policy.zip").is_file(),
            )
            for r in data["rounds"]
        ],
        chosen_by=cast(ChosenBy, summary.chosen_by),
    )


def agent_file(context: AppContext, session_id: str, name: str) -> tuple[Path, AgentSummary]:
    """The path of the finished session's ``agent.mp4`` or ``agent.zip``. Raises
    NotFoundError, ConflictError."""
    summary, directory = _summary(context, session_id)
    path = directory / name
    if name == AGENT_VIDEO and summary.video is not None:
        path = directory / summary.video.file  # a picked round's clip, or agent.mp4
    if name not in (AGENT_VIDEO, AGENT_ZIP) or not path.is_file():
        raise NotFoundError(f"session {session_id} has no {name}")
    return path, summary
