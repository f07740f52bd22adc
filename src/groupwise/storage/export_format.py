"""The session export's file formats, JSONL and Parquet: writing and parsing them.

The format is documented for its readers in docs/export.md (with pandas and Hugging Face
`datasets` examples); in short:

JSONL (``format: groupwise.session-export/1``), one JSON object a line:

    {"type": "session", "format": …, "id", "env", "mode", "settings", "annotator",
     "phase", "round", "created_at"}
    {"type": "round", "round": r, "pool_dir", "opened_at", "shown_at", "closed_at",
     "close_reason", "views": [{"annotator_id", "shown_at"}, …]}  …
    {"type": "annotator", "id": "owner" | "a-…", "name", "comparisons", "pairs", "shown_s",
     "agreement": {"kappa", "share", "n"}, "model_agreement": {"share", "n"},
     "removed"}  … the owner first (docs/teams.md)
    {"type": "behaviour", "round": r, "id": "b<i>", "obs": [[…] × L], "acts": [[…] × L],
     "true_rewards": [… L] or null}  … only in an export with states
    {"type": "judgement", "id", "seq", "client_id", "round", "left": [names],
     "right": [names], "label", "source", "seconds", "edits", "annotator" (who made it,
     by name), "annotator_id" ("owner" or theirs), "created_at", "undone",
     "pairs": [{"a", "b", "label"}, …]}  … oldest first

Parquet: one row per judgement with the judgement fields as columns (``pairs`` a list of
structs); the session, round and annotator objects are in the schema metadata under
``groupwise.session``, ``groupwise.rounds`` and ``groupwise.annotators`` (JSON). With
states, each row also holds its groups' arrays, aligned with ``left`` / ``right``:
``left_obs`` / ``right_obs`` (m, L, obs_dim) float32, ``left_acts`` / ``right_acts``
(m, L, act_dim) float32, and, when exported, ``left_true_rewards`` /
``right_true_rewards`` (m, L) float64.

Undone judgements are exported (flagged, without pairs): the export is the record of truth.
True returns and rewards are exported only with states and only where the caller allows
(`groupwise.storage.export`). Reading a session into a `SessionExport` and an export into a
new session is `groupwise.storage.export`; nothing here touches the database.

This module holds the export's lines (validated on parsing) and `SessionExport`; the files
are written and parsed by `export_jsonl` and `export_parquet`.
"""

from dataclasses import dataclass
from datetime import datetime
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from groupwise.storage.errors import InvalidError
from groupwise.storage.settings import SessionSettings
from groupwise.storage.states import BehaviourStates

FORMAT = "groupwise.session-export/1"


class ExportLine(BaseModel):
    """A line of the export (or a part of one): unknown fields are ignored, text with a NUL
    is refused."""

    model_config = ConfigDict(extra="ignore", frozen=True)

    @field_validator("*", mode="after")
    @classmethod
    def _no_nul(cls, value: Any) -> Any:
        # PostgreSQL's text cannot hold NUL (`storage.errors.check_text`): refused on import
        texts = value if isinstance(value, list) else [value]
        if any(isinstance(v, str) and "\x00" in v for v in texts):
            raise ValueError("contains a NUL character")
        return value


class SessionLine(ExportLine):
    type: Literal["session"] = "session"
    format: Literal["groupwise.session-export/1"] = "groupwise.session-export/1"
    id: str = Field(max_length=100)
    env: str = Field(max_length=200)
    mode: Literal["groupwise", "pairwise"]
    settings: SessionSettings
    annotator: str = Field(default="", max_length=200)
    phase: str = Field(max_length=16)
    round: int = Field(ge=0, le=10_000)
    created_at: datetime


class ViewLine(ExportLine):
    """When one person first showed a round in a page; their time shown counts from then
    to the round's close (`storage.team`)."""

    annotator_id: str = Field(min_length=1, max_length=32)
    shown_at: datetime


class RoundLine(ExportLine):
    type: Literal["round"] = "round"
    round: int = Field(ge=0, le=10_000)
    pool_dir: str | None = Field(default=None, max_length=1000)
    opened_at: datetime | None = None
    shown_at: datetime | None = None
    closed_at: datetime | None = None
    close_reason: str | None = Field(default=None, max_length=32)
    views: list[ViewLine] = Field(default_factory=list, max_length=10_000)


class PairLine(ExportLine):
    a: str = Field(pattern=r"^b\d{1,6}$")
    b: str = Field(pattern=r"^b\d{1,6}$")
    label: float = Field(ge=0, le=1)


class JudgementLine(ExportLine):
    type: Literal["judgement"] = "judgement"
    id: int
    seq: int = Field(ge=0)
    client_id: str = Field(min_length=1, max_length=100)
    round: int = Field(ge=0, le=10_000)
    left: list[str] = Field(min_length=1, max_length=200)
    right: list[str] = Field(min_length=1, max_length=200)
    label: Literal["left", "right", "equal"]
    source: Literal["suggested", "explored", "pairwise", "simulated"]
    seconds: float = Field(default=0.0, ge=0)
    edits: int = Field(default=0, ge=0)
    annotator: str = Field(default="", max_length=200)
    annotator_id: str = Field(default="owner", min_length=1, max_length=32)
    created_at: datetime
    undone: bool = False
    pairs: list[PairLine] = Field(default_factory=list, max_length=10_000)


class AgreementLine(ExportLine):
    kappa: float | None = None
    share: float | None = Field(default=None, ge=0, le=1)
    n: int = Field(default=0, ge=0)


class ModelAgreementLine(ExportLine):
    share: float | None = Field(default=None, ge=0, le=1)
    n: int = Field(default=0, ge=0)


class AnnotatorLine(ExportLine):
    """Someone who taught the session, with their counters and agreement when exported
    (`storage.team`)."""

    type: Literal["annotator"] = "annotator"
    id: str = Field(min_length=1, max_length=32)
    name: str = Field(max_length=200)
    comparisons: int = Field(default=0, ge=0)
    pairs: int = Field(default=0, ge=0)
    shown_s: float = Field(default=0.0, ge=0)
    agreement: AgreementLine = AgreementLine()
    model_agreement: ModelAgreementLine = ModelAgreementLine()
    removed: bool = False


class BehaviourLine(ExportLine):
    type: Literal["behaviour"] = "behaviour"
    round: int = Field(ge=0, le=10_000)
    id: str = Field(pattern=r"^b\d{1,6}$")
    obs: list[list[float]] = Field(min_length=1, max_length=100_000)
    acts: list[list[float]] = Field(min_length=1, max_length=100_000)
    true_rewards: list[float] | None = Field(default=None, max_length=100_000)


@dataclass(frozen=True)
class SessionExport:
    """A session's export, whichever file format it came from or goes to; `behaviours`
    (one per round that has judgements) only in an export with states."""

    session: SessionLine
    rounds: tuple[RoundLine, ...]
    judgements: tuple[JudgementLine, ...]
    behaviours: tuple[BehaviourStates, ...] = ()
    annotators: tuple[AnnotatorLine, ...] = ()


def parse_line(kind: type[ExportLine], obj: Any, where: str) -> ExportLine:
    """`obj` as a `kind` line. Raises InvalidError naming `where` and the first bad field."""
    try:
        return kind.model_validate(obj)
    except ValidationError as error:
        first = error.errors()[0]
        field = ".".join(str(part) for part in first["loc"]) or "value"
        raise InvalidError(f"{where}: {field}: {first['msg']}") from None


def states_of(lines: list[BehaviourLine]) -> tuple[BehaviourStates, ...]:
    """The behaviour lines as one `BehaviourStates` per round (in order of first line)."""
    grouped: dict[int, list[BehaviourLine]] = {}
    for line in lines:
        grouped.setdefault(line.round, []).append(line)
    found = []
    for round_index, group in grouped.items():
        rewards = [line.true_rewards for line in group]
        if any(r is None for r in rewards) and any(r is not None for r in rewards):
            raise InvalidError(f"round {round_index}: true_rewards for some behaviours only")
        try:
            obs = np.asarray([line.obs for line in group], dtype=np.float32)
            acts = np.asarray([line.acts for line in group], dtype=np.float32)
            true = None if rewards[0] is None else np.asarray(rewards, dtype=np.float64)
        except ValueError:
            raise InvalidError(f"round {round_index}: behaviours of different shapes") from None
        names = tuple(line.id for line in group)
        found.append(BehaviourStates(round_index, names, obs, acts, true))
    return tuple(found)
