"""A round's pool: the behaviour tree and its clips, suggestion edges, group suggestions,
and the event that a round changed."""

from typing import Annotated, Literal

from pydantic import Field

from groupwise.server.schemas.base import BehaviourId, In, Out
from groupwise.storage.settings import MAX_GROUP


class TreeNodeOut(Out):
    """A node of the behaviour tree; leaves carry their behaviour's index, clip and poster."""

    id: str
    kind: Literal["merge", "padding", "leaf"]
    level: int
    size: int
    children: list["TreeNodeOut"]
    behaviour: int | None = None
    clip: str | None = None
    poster: str | None = None


class ClipTiming(Out):
    """How a pool's clips show its behaviours (docs/app.md, "Clips"; `clips.timing`)."""

    steps: int = Field(description="L, env steps per behaviour")
    stride: int = Field(description="a frame every stride-th step")
    frames: int = Field(description="frames per clip, ⌈steps / stride⌉")
    fps: float = Field(description="playback frames per second, 1 / (stride · step_seconds)")
    seconds: float = Field(description="simulated time a behaviour covers, steps · step_seconds")
    speed: float = Field(description="playback speed relative to simulated time (1: real speed)")
    step_seconds: float = Field(description="dt, simulated seconds per env step")


class RoundTree(Out):
    round: int
    levels: int
    clip: ClipTiming | None = Field(
        default=None, description="the pool's clip timing (null: a pool from before it)"
    )
    tree: TreeNodeOut
    medoids: dict[str, list[str]] = Field(
        description="inner node id → up to 3 representative behaviour ids"
    )
    compared: list[str] = Field(description="behaviours already in a judgement of the round")


class Edge(Out):
    a: str
    b: str
    score: float = Field(gt=0, le=1)


class SuggestionRequest(In):
    exclude: (
        Annotated[
            list[Annotated[list[BehaviourId], Field(max_length=MAX_GROUP)]], Field(max_length=200)
        ]
        | None
    ) = Field(
        default=None,
        description="queries to skip, as consecutive [left ids], [right ids] lists "
        "(one query: [[left], [right]])",
    )


class Suggestion(Out):
    id: int = Field(
        description="the suggestion's id; a judgement event naming it (suggestion_id) answered it"
    )
    left: list[str]
    right: list[str]
    left_node: str
    right_node: str
    score: float


class SuggestionOut(Out):
    suggestion: Suggestion | None


class RoundEvent(Out):
    round: int
