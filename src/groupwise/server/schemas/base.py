"""The schemas' base models, the field types they share, the error answer and the limits
the page needs as numbers."""

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from groupwise.episodes.ids import BEHAVIOUR_PREFIX, behaviour_id
from groupwise.storage.settings import MAX_GROUP

Phase = Literal["preparing", "ready", "training", "finishing", "finished", "failed"]
Mode = Literal["groupwise", "pairwise"]
Label = Literal["left", "right", "equal"]
Source = Literal["suggested", "explored", "pairwise"]
BehaviourId = Annotated[
    str,
    Field(pattern=rf"^{BEHAVIOUR_PREFIX}\d{{1,6}}$", max_length=8, examples=[behaviour_id(17)]),
]


def limits() -> dict[str, int]:
    """The server's limits that the page needs as numbers (``web/src/limits.json``)."""
    return {"max_group": MAX_GROUP}


class In(BaseModel):
    """A request body: unknown fields are rejected."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class Out(BaseModel):
    """A response body."""

    model_config = ConfigDict(frozen=True)


class ErrorOut(Out):
    """Every 4xx answer: one clear sentence."""

    detail: str
