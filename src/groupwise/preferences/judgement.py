"""A judgement: the stored record of one comparison of two groups (SPEC §6)."""

from dataclasses import dataclass, field
from enum import StrEnum

LEFT_BETTER = 1.0
RIGHT_BETTER = 0.0
EQUAL = 0.5
LABELS = (LEFT_BETTER, RIGHT_BETTER, EQUAL)
MAX_GROUP = 8
"""Largest group of one comparison (paper §6: 8 keeps a comparison humanly possible)."""


class Source(StrEnum):
    """Where a comparison came from (the user study compares these)."""

    SUGGESTED = "suggested"
    EXPLORED = "explored"
    PAIRWISE = "pairwise"
    SIMULATED = "simulated"


@dataclass(frozen=True)
class Judgement:
    """Both groups (as pool indices), the label and how it was given.

    `label` is 1.0 when the left group is better, 0.0 when the right one is, 0.5 for equal.
    A pairwise comparison is a judgement of two groups of size one.
    """

    left: tuple[int, ...]
    right: tuple[int, ...]
    label: float
    source: Source = Source.SIMULATED
    seconds: float = 0.0
    edits: int = 0
    annotator: str = field(default="")

    def __post_init__(self) -> None:
        if not self.left or not self.right:
            raise ValueError("both groups of a judgement need at least one behaviour")
        if len(set(self.left)) != len(self.left) or len(set(self.right)) != len(self.right):
            raise ValueError("a group lists the same behaviour twice")
        both = set(self.left) & set(self.right)
        if both:
            raise ValueError(f"behaviours {sorted(both)} are in both groups")
        if self.label not in LABELS:
            raise ValueError(f"label must be one of {LABELS}, got {self.label}")
