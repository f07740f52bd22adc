"""A judgement of two groups, as a page sends it and as the server records it, with its
preference pairs."""

from datetime import datetime

from pydantic import Field

from groupwise.server.schemas.base import BehaviourId, In, Label, Out, Source
from groupwise.storage.settings import MAX_GROUP


class JudgementIn(In):
    client_id: str = Field(min_length=1, max_length=100, description="unique per comparison")
    round: int = Field(ge=0, le=10_000)
    left: list[BehaviourId] = Field(min_length=1, max_length=MAX_GROUP)
    right: list[BehaviourId] = Field(min_length=1, max_length=MAX_GROUP)
    label: Label
    source: Source
    seconds: float = Field(default=0.0, ge=0, le=86_400)
    edits: int = Field(default=0, ge=0, le=1_000_000)
    annotator: str = Field(
        default="",
        max_length=200,
        description="the owner's free-text name for it; an annotator's judgement takes "
        "their name (docs/teams.md)",
    )


class PairOut(Out):
    a: str
    b: str
    label: float = Field(description="P(a preferred): 1, 0.5 or 0")


class AnnotatorRef(Out):
    """Who made a judgement."""

    id: str = Field(description='"owner" or the annotator\'s id')
    name: str


class JudgementOut(Out):
    id: int
    client_id: str
    round: int
    left: list[str]
    right: list[str]
    label: Label
    source: str
    seconds: float
    edits: int
    annotator: AnnotatorRef
    suggestion_id: int | None = Field(
        default=None, description="the group suggestion it answered (others drop it)"
    )
    created_at: datetime
    undone: bool
    pairs: list[PairOut]
