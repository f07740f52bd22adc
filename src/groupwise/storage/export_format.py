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
"""

import io
import json
from dataclasses import dataclass
from datetime import datetime
from typing import Any, Literal

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from groupwise.storage.errors import InvalidError
from groupwise.storage.settings import SessionSettings
from groupwise.storage.states import BehaviourStates

FORMAT = "groupwise.session-export/1"
_SESSION_KEY = b"groupwise.session"
_ROUNDS_KEY = b"groupwise.rounds"
_ANNOTATORS_KEY = b"groupwise.annotators"


class _Strict(BaseModel):
    model_config = ConfigDict(extra="ignore", frozen=True)

    @field_validator("*", mode="after")
    @classmethod
    def _no_nul(cls, value: Any) -> Any:
        # PostgreSQL's text cannot hold NUL (`storage.errors.check_text`): refused on import
        texts = value if isinstance(value, list) else [value]
        if any(isinstance(v, str) and "\x00" in v for v in texts):
            raise ValueError("contains a NUL character")
        return value


class SessionLine(_Strict):
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


class ViewLine(_Strict):
    """When one person first showed a round in a page; their time shown counts from then
    to the round's close (`storage.team`)."""

    annotator_id: str = Field(min_length=1, max_length=32)
    shown_at: datetime


class RoundLine(_Strict):
    type: Literal["round"] = "round"
    round: int = Field(ge=0, le=10_000)
    pool_dir: str | None = Field(default=None, max_length=1000)
    opened_at: datetime | None = None
    shown_at: datetime | None = None
    closed_at: datetime | None = None
    close_reason: str | None = Field(default=None, max_length=32)
    views: list[ViewLine] = Field(default_factory=list, max_length=10_000)


class PairLine(_Strict):
    a: str = Field(pattern=r"^b\d{1,6}$")
    b: str = Field(pattern=r"^b\d{1,6}$")
    label: float = Field(ge=0, le=1)


class JudgementLine(_Strict):
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


class AgreementLine(_Strict):
    kappa: float | None = None
    share: float | None = Field(default=None, ge=0, le=1)
    n: int = Field(default=0, ge=0)


class ModelAgreementLine(_Strict):
    share: float | None = Field(default=None, ge=0, le=1)
    n: int = Field(default=0, ge=0)


class AnnotatorLine(_Strict):
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


class BehaviourLine(_Strict):
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


def _states_of(lines: list[BehaviourLine]) -> tuple[BehaviourStates, ...]:
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


def to_jsonl(export: SessionExport) -> bytes:
    """The JSONL bytes of an export (module docstring)."""
    head = [
        line.model_dump_json().encode()
        for line in (export.session, *export.rounds, *export.annotators)
    ]
    tail = [line.model_dump_json().encode() for line in export.judgements]
    states = [_behaviour_json(states, i) for states in export.behaviours for i in
              range(len(states.names))]  # fmt: skip
    return b"".join(line + b"\n" for line in (*head, *states, *tail))


def _behaviour_json(states: BehaviourStates, i: int) -> bytes:
    # float32 → float → JSON's shortest repr reads back to the same float32
    line = {
        "type": "behaviour",
        "round": states.round,
        "id": states.names[i],
        "obs": states.obs[i].tolist(),
        "acts": states.acts[i].tolist(),
        "true_rewards": None if states.true_rewards is None else states.true_rewards[i].tolist(),
    }
    return json.dumps(line, separators=(",", ":")).encode()


def from_jsonl(data: bytes) -> SessionExport:
    """Parse a JSONL export. Raises InvalidError naming the first bad line."""
    session: SessionLine | None = None
    rounds: list[RoundLine] = []
    judgements: list[JudgementLine] = []
    behaviours: list[BehaviourLine] = []
    annotators: list[AnnotatorLine] = []
    kinds: dict[str, type[_Strict]] = {
        "session": SessionLine,
        "round": RoundLine,
        "annotator": AnnotatorLine,
        "behaviour": BehaviourLine,
        "judgement": JudgementLine,
    }
    for number, line in enumerate(data.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            obj = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError):
            raise InvalidError(f"line {number} of the export is not JSON") from None
        kind = kinds.get(str(obj.get("type"))) if isinstance(obj, dict) else None
        if kind is None:
            raise InvalidError(
                f"line {number} has no known type (session, round, annotator, behaviour, judgement)"
            )
        parsed = _parse(kind, obj, f"line {number}")
        if isinstance(parsed, SessionLine):
            if session is not None:
                raise InvalidError(f"line {number} is a second session line")
            session = parsed
        elif isinstance(parsed, RoundLine):
            rounds.append(parsed)
        elif isinstance(parsed, JudgementLine):
            judgements.append(parsed)
        elif isinstance(parsed, BehaviourLine):
            behaviours.append(parsed)
        elif isinstance(parsed, AnnotatorLine):
            annotators.append(parsed)
    if session is None:
        raise InvalidError("the export has no session line")
    return SessionExport(
        session, tuple(rounds), tuple(judgements), _states_of(behaviours), tuple(annotators)
    )


def _parse(kind: type[_Strict], obj: Any, where: str) -> _Strict:
    try:
        return kind.model_validate(obj)
    except ValidationError as error:
        first = error.errors()[0]
        field = ".".join(str(part) for part in first["loc"]) or "value"
        raise InvalidError(f"{where}: {field}: {first['msg']}") from None


_PAIR = pa.struct([("a", pa.string()), ("b", pa.string()), ("label", pa.float64())])
_SCHEMA = pa.schema(
    [
        ("id", pa.int64()),
        ("seq", pa.int64()),
        ("client_id", pa.string()),
        ("round", pa.int64()),
        ("left", pa.list_(pa.string())),
        ("right", pa.list_(pa.string())),
        ("label", pa.string()),
        ("source", pa.string()),
        ("seconds", pa.float64()),
        ("edits", pa.int64()),
        ("annotator", pa.string()),
        ("annotator_id", pa.string()),
        ("created_at", pa.timestamp("us", tz="UTC")),
        ("undone", pa.bool_()),
        ("pairs", pa.list_(_PAIR)),
    ]
)


_STATE_COLUMNS = {"obs": pa.float32(), "acts": pa.float32(), "true_rewards": pa.float64()}
"""The per-group state columns (``left_obs`` …) and their value types."""


def to_parquet(export: SessionExport) -> bytes:
    """The Parquet bytes of an export (module docstring)."""
    rows = [j.model_dump(exclude={"type"}) for j in export.judgements]
    metadata = {
        _SESSION_KEY: export.session.model_dump_json().encode(),
        _ROUNDS_KEY: json.dumps([r.model_dump(mode="json") for r in export.rounds]).encode(),
        _ANNOTATORS_KEY: json.dumps(
            [a.model_dump(mode="json") for a in export.annotators]
        ).encode(),
    }
    table = pa.Table.from_pylist(rows, schema=_SCHEMA)
    if export.behaviours:
        table = _with_states(table, export)
    sink = io.BytesIO()
    pq.write_table(table.replace_schema_metadata(metadata), sink)
    return sink.getvalue()


def _with_states(table: pa.Table, export: SessionExport) -> pa.Table:
    """`table` with each judgement's groups' arrays appended as columns."""
    by_round = {states.round: states for states in export.behaviours}
    rewards = all(states.true_rewards is not None for states in by_round.values())
    for side in ("left", "right"):
        groups: dict[str, list[np.ndarray]] = {name: [] for name in _STATE_COLUMNS}
        for j in export.judgements:
            states = by_round.get(j.round)
            if states is None:
                raise InvalidError(f"the export has no states of round {j.round}")
            rows = [states.row(name) for name in getattr(j, side)]
            groups["obs"].append(states.obs[rows])
            groups["acts"].append(states.acts[rows])
            if rewards:
                groups["true_rewards"].append(states.true_rewards[rows])  # type: ignore[index]  # set when rewards
        for name, value_type in _STATE_COLUMNS.items():
            if name != "true_rewards" or rewards:
                column = _nested(groups[name], value_type)
                table = table.append_column(f"{side}_{name}", column)
    return table


def _nested(arrays: list[np.ndarray], value_type: pa.DataType) -> pa.Array:
    """One list per array: arrays of shape (m_i, *shape) as nested Arrow lists (m_i, …),
    built from offsets without going through Python lists."""
    inner_shape = arrays[0].shape[1:] if arrays else ()
    flat = np.concatenate([a.reshape(-1) for a in arrays]) if arrays else np.zeros(0)
    nested: pa.Array = pa.array(flat, type=value_type)
    for size in reversed(inner_shape):
        offsets = np.arange(0, len(nested) + 1, size, dtype=np.int32)
        nested = pa.ListArray.from_arrays(pa.array(offsets), nested)
    counts = np.array([len(a) for a in arrays], dtype=np.int32)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    return pa.ListArray.from_arrays(pa.array(offsets), nested)


def _states_from_table(table: pa.Table, judgements: list[JudgementLine]) -> list[BehaviourLine]:
    """The behaviours of a Parquet export with states, each once (its first occurrence)."""
    names = set(table.column_names)
    if not {"left_obs", "right_obs", "left_acts", "right_acts"} <= names:
        return []
    rewards = {"left_true_rewards", "right_true_rewards"} <= names
    seen: set[tuple[int, str]] = set()
    lines = []
    for side in ("left", "right"):
        obs = table.column(f"{side}_obs").to_pylist()
        acts = table.column(f"{side}_acts").to_pylist()
        true = table.column(f"{side}_true_rewards").to_pylist() if rewards else None
        for i, j in enumerate(judgements):
            group = getattr(j, side)
            if len(obs[i] or ()) != len(group) or len(acts[i] or ()) != len(group):
                raise InvalidError(f"row {i}: {side}_obs or {side}_acts do not match {side}")
            for k, name in enumerate(group):
                if (j.round, name) in seen:
                    continue
                seen.add((j.round, name))
                line = {"round": j.round, "id": name, "obs": obs[i][k], "acts": acts[i][k]}
                if true is not None:
                    line["true_rewards"] = (true[i] or [None] * len(group))[k]
                parsed = _parse(BehaviourLine, line, f"row {i}, {side} {name}")
                assert isinstance(parsed, BehaviourLine)
                lines.append(parsed)
    return lines


def from_parquet(data: bytes) -> SessionExport:
    """Parse a Parquet export. Raises InvalidError when it is not one."""
    try:
        table = pq.read_table(io.BytesIO(data))
    except (pa.ArrowException, OSError, ValueError):
        raise InvalidError("the body is not a Parquet file") from None
    metadata = table.schema.metadata or {}
    if _SESSION_KEY not in metadata:
        raise InvalidError("the Parquet file is not a groupwise session export")
    try:
        session_obj = json.loads(metadata[_SESSION_KEY])
        rounds_obj = json.loads(metadata.get(_ROUNDS_KEY, b"[]"))
        annotators_obj = json.loads(metadata.get(_ANNOTATORS_KEY, b"[]"))
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise InvalidError("the Parquet file's session metadata is not JSON") from None
    if not isinstance(rounds_obj, list):
        raise InvalidError("the Parquet file's round metadata is not a list")
    if not isinstance(annotators_obj, list):
        raise InvalidError("the Parquet file's annotator metadata is not a list")
    annotators = [
        _parse(AnnotatorLine, {**a, "type": "annotator"} if isinstance(a, dict) else a,
               f"annotator {i}")
        for i, a in enumerate(annotators_obj)
    ]  # fmt: skip
    session = _parse(SessionLine, session_obj, "session metadata")
    rounds = [_parse(RoundLine, r, f"round {i}") for i, r in enumerate(rounds_obj)]
    plain = table.select([name for name in _SCHEMA.names if name in table.column_names])
    parsed = [
        _parse(JudgementLine, {**row, "type": "judgement"}, f"row {i}")
        for i, row in enumerate(plain.to_pylist())
    ]
    judgements = [j for j in parsed if isinstance(j, JudgementLine)]
    assert isinstance(session, SessionLine)
    return SessionExport(
        session,
        tuple(r for r in rounds if isinstance(r, RoundLine)),
        tuple(judgements),
        _states_of(_states_from_table(table, judgements)),
        tuple(a for a in annotators if isinstance(a, AnnotatorLine)),
    )
