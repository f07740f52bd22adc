"""How far annotators agree with each other and with a reward model, on preference pairs.

A label is P(a preferred) of a pair (a, b): 1, 0.5 or 0, three categories. Two people's
labels of one pair are compared in one orientation (`oriented`): the pair's behaviours in
sorted order. Items are keyed by anything hashable (the app keys them by round and the
oriented pair, since behaviour ids are a round's own).

- `cohen_kappa`: Cohen's κ = (p_o − p_e) / (1 − p_e) of two raters over the same items,
  p_o the share of items they label alike and p_e the share expected by chance from each
  rater's own label frequencies (Cohen 1960, "A coefficient of agreement for nominal
  scales"). Undefined (None) without items and when chance agreement is certain (both
  raters used one and the same label throughout).
- `rater_agreement`: one annotator against all the others: every item they share with
  another annotator is one rating pair (an item shared with two others counts twice).
- `model_agreement`: the share of an annotator's strict preferences (label 1 or 0) whose
  direction a model's predicted margin (predicted return of a minus that of b) shares;
  equal labels and margins of exactly 0 are not counted.
"""

from collections import Counter
from collections.abc import Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TypeVar

K = TypeVar("K", bound=Hashable)
"""An item's key: anything hashable."""


@dataclass(frozen=True)
class Agreement:
    """One annotator's agreement with the others on the pairs they share."""

    kappa: float | None
    """Cohen's κ; None when n = 0 or chance agreement is 1."""
    share: float | None
    """Share of the n rating pairs labelled alike; None when n = 0."""
    n: int
    """Rating pairs the numbers rest on."""


@dataclass(frozen=True)
class ModelAgreement:
    """One annotator's strict preferences against a reward model's predicted margins."""

    share: float | None
    """Share of the n preferences the model orders the same way; None when n = 0."""
    n: int


def oriented(a: str, b: str, label: float) -> tuple[tuple[str, str], float]:
    """The pair in sorted order and P(its first preferred): ("b7", "b3", 1.0) → (("b3",
    "b7"), 0.0)."""
    return ((a, b), label) if a <= b else ((b, a), 1.0 - label)


def cohen_kappa(first: Sequence[float], second: Sequence[float]) -> float | None:
    """Cohen's κ of two raters' labels of the same items (module docstring).

    Raises ValueError when the sequences differ in length.
    """
    if len(first) != len(second):
        raise ValueError(f"{len(first)} labels against {len(second)}: rate the same items")
    n = len(first)
    if n == 0:
        return None
    observed = sum(x == y for x, y in zip(first, second, strict=True)) / n
    counts_first, counts_second = Counter(first), Counter(second)
    expected = sum(counts_first[c] * counts_second[c] for c in counts_first) / (n * n)
    if expected >= 1.0:
        return None
    return (observed - expected) / (1.0 - expected)


def rater_agreement(mine: Mapping[K, float], others: Iterable[Mapping[K, float]]) -> Agreement:
    """`mine` against each of `others` on the items both labelled (module docstring)."""
    first: list[float] = []
    second: list[float] = []
    for theirs in others:
        for key in mine.keys() & theirs.keys():
            first.append(mine[key])
            second.append(theirs[key])
    n = len(first)
    if n == 0:
        return Agreement(kappa=None, share=None, n=0)
    share = sum(x == y for x, y in zip(first, second, strict=True)) / n
    return Agreement(kappa=cohen_kappa(first, second), share=share, n=n)


def model_agreement(labels: Mapping[K, float], margins: Mapping[K, float]) -> ModelAgreement:
    """The share of strict `labels` (P(a preferred) 1 or 0) whose direction the model's
    `margins` (predicted return of a minus b, same keys) share; other items not counted."""
    agree = n = 0
    for key, label in labels.items():
        margin = margins.get(key)
        if label == 0.5 or margin is None or margin == 0:
            continue
        n += 1
        agree += (margin > 0) == (label > 0.5)
    return ModelAgreement(share=agree / n if n else None, n=n)
