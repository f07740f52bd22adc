"""The pairwise mode: the next pair of behaviours to compare, and skipping one."""

from pydantic import Field

from groupwise.server.schemas.base import BehaviourId, In, Out
from groupwise.server.schemas.rounds import ClipTiming


class PairQuery(Out):
    left: str
    right: str
    left_clip: str
    right_clip: str
    left_poster: str
    right_poster: str


class PairwiseNext(Out):
    pair: PairQuery | None
    following: PairQuery | None
    clip: ClipTiming | None = Field(
        default=None, description="the open round's clip timing (null: a pool from before it)"
    )


class PairSkip(In):
    left: BehaviourId
    right: BehaviourId
