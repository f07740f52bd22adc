"""The session export's file formats, JSONL and Parquet: writing and parsing them.

JSONL (``format: groupwise.session-export/1``), one JSON object a line:

    {"type": "session", "format": …, "id", "env", "mode", "settings", "annotator",
     "phase", "round", "created_at"}
    {"type": "round", "round": r, "pool_dir", "opened_at", "shown_at", "closed_at",
     "close_reason"}  …
    {"type": "judgement", "id", "seq", "client_id", "round", "left": [names],
     "right": [names], "label", "source", "seconds", "edits", "annotator", "created_at",
     "undone", "pairs": [{"a", "b", "label"}, …]}  … oldest first

Parquet: one row per judgement with the judgement fields as columns (``pairs`` a list of
structs); the session and round objects are in the schema metadata under
``groupwise.session`` and ``groupwise.rounds`` (JSON).

Undone judgements are exported (flagged, without pairs): the export is the record of truth.
True returns are not exported (the export is downloaded through the page). Reading a
session into a `SessionExport` and an export into a new session is
`groupwise.storage.export`; nothing here touches the database.
"""

import io
import json
from dataclasses import dataclass
from datetime import datetime
from typing import Any, Literal

import pyarrow as pa
import pyarrow.parquet as pq
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from groupwise.storage.errors import InvalidError
from groupwise.storage.settings import SessionSettings

FORMAT = "groupwise.session-export/1"
_SESSION_KEY = b"groupwise.session"
_ROUNDS_KEY = b"groupwise.rounds"


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


class RoundLine(_Strict):
    type: Literal["round"] = "round"
    round: int = Field(ge=0, le=10_000)
    pool_dir: str | None = Field(default=None, max_length=1000)
    opened_at: datetime | None = None
    shown_at: datetime | None = None
    closed_at: datetime | None = None
    close_reason: str | None = Field(default=None, max_length=32)


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
    created_at: datetime
    undone: bool = False
    pairs: list[PairLine] = Field(default_factory=list, max_length=10_000)


@dataclass(frozen=True)
class SessionExport:
    """A session's export, whichever file format it came from or goes to."""

    session: SessionLine
    rounds: tuple[RoundLine, ...]
    judgements: tuple[JudgementLine, ...]


def to_jsonl(export: SessionExport) -> bytes:
    """The JSONL bytes of an export (module docstring)."""
    lines = [export.session, *export.rounds, *export.judgements]
    return b"".join(line.model_dump_json().encode() + b"\n" for line in lines)


def from_jsonl(data: bytes) -> SessionExport:
    """Parse a JSONL export. Raises InvalidError naming the first bad line."""
    session: SessionLine | None = None
    rounds: list[RoundLine] = []
    judgements: list[JudgementLine] = []
    kinds: dict[str, type[_Strict]] = {
        "session": SessionLine,
        "round": RoundLine,
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
            raise InvalidError(f"line {number} has no known type (session, round, judgement)")
        parsed = _parse(kind, obj, f"line {number}")
        if isinstance(parsed, SessionLine):
            if session is not None:
                raise InvalidError(f"line {number} is a second session line")
            session = parsed
        elif isinstance(parsed, RoundLine):
            rounds.append(parsed)
        elif isinstance(parsed, JudgementLine):
            judgements.append(parsed)
    if session is None:
        raise InvalidError("the export has no session line")
    return SessionExport(session, tuple(rounds), tuple(judgements))


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
        ("created_at", pa.timestamp("us", tz="UTC")),
        ("undone", pa.bool_()),
        ("pairs", pa.list_(_PAIR)),
    ]
)


def to_parquet(export: SessionExport) -> bytes:
    """The Parquet bytes of an export (module docstring)."""
    rows = [j.model_dump(exclude={"type"}) for j in export.judgements]
    metadata = {
        _SESSION_KEY: export.session.model_dump_json().encode(),
        _ROUNDS_KEY: json.dumps([r.model_dump(mode="json") for r in export.rounds]).encode(),
    }
    table = pa.Table.from_pylist(rows, schema=_SCHEMA.with_metadata(metadata))
    sink = io.BytesIO()
    pq.write_table(table, sink)
    return sink.getvalue()


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
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise InvalidError("the Parquet file's session metadata is not JSON") from None
    if not isinstance(rounds_obj, list):
        raise InvalidError("the Parquet file's round metadata is not a list")
    session = _parse(SessionLine, session_obj, "session metadata")
    rounds = [_parse(RoundLine, r, f"round {i}") for i, r in enumerate(rounds_obj)]
    judgements = [
        _parse(JudgementLine, {**row, "type": "judgement"}, f"row {i}")
        for i, row in enumerate(table.to_pylist())
    ]
    assert isinstance(session, SessionLine)
    return SessionExport(
        session,
        tuple(r for r in rounds if isinstance(r, RoundLine)),
        tuple(j for j in judgements if isinstance(j, JudgementLine)),
    )
