"""A session: what creates it and its state as a page sees it."""

from datetime import datetime

from pydantic import Field

from groupwise.server.schemas.annotators import AnnotatorOut, MeOut
from groupwise.server.schemas.base import In, Mode, Out, Phase
from groupwise.storage.settings import SessionSettings


class SessionCreate(In):
    env: str | None = Field(
        default=None,
        min_length=1,
        max_length=200,
        examples=["GridWorld"],
        description="the env (required unless settings.dataset names a recorded dataset, "
        "whose own env is the default)",
    )
    mode: Mode = "groupwise"
    settings: SessionSettings = SessionSettings()
    annotator: str = Field(default="", max_length=200)


class Progress(Out):
    phase: str = Field(description="the step the worker is on, e.g. pool, reward, ppo")
    fraction: float = Field(ge=0, le=1)
    message: str


class Timer(Out):
    elapsed_s: float = Field(description="seconds the open round's timer has run")
    budget_s: float = Field(description="the round's time budget (0 = no limit)")
    paused: bool
    running: bool = Field(
        description="whether the timer runs now (the round is open, shown and not paused)"
    )
    shown_at: datetime | None = Field(
        default=None,
        description="when a page first showed the current round; its timer runs from then "
        "(null: not shown yet, POST …/rounds/{r}/shown)",
    )


class Counts(Out):
    comparisons_round: int
    pairs_round: int
    comparisons_total: int
    pairs_total: int


class SessionState(Out):
    """Everything a reloaded page needs but the tree."""

    id: str
    env: str
    mode: Mode
    settings: SessionSettings
    annotator: str
    round: int
    rounds: int
    phase: Phase
    progress: Progress
    error: str | None
    failed_phase: Phase | None = Field(
        default=None,
        description="while failed: the step that failed (preparing, training or finishing), "
        "what POST /retry runs again",
    )
    timer: Timer
    counts: Counts
    created_at: datetime
    origin: str | None = Field(default=None, description="the exported session an import came from")
    me: MeOut = Field(description="who the caller is in this session")
    annotators: list[AnnotatorOut] = Field(
        description="the owner, then every annotator of the session (docs/teams.md)"
    )
