"""The session export as Parquet, one row per judgement with the session, rounds and
annotators in the schema's metadata (`export_format`'s docstring and docs/export.md):
writing it and parsing it."""

import io
import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from groupwise.storage.errors import InvalidError
from groupwise.storage.export_format import (
    AnnotatorLine,
    BehaviourLine,
    JudgementLine,
    RoundLine,
    SessionExport,
    SessionLine,
    parse_line,
    states_of,
)

_SESSION_KEY = b"groupwise.session"
_ROUNDS_KEY = b"groupwise.rounds"
_ANNOTATORS_KEY = b"groupwise.annotators"


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
    """The Parquet bytes of an export (`export_format`'s docstring)."""
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
                parsed = parse_line(BehaviourLine, line, f"row {i}, {side} {name}")
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
        parse_line(AnnotatorLine, {**a, "type": "annotator"} if isinstance(a, dict) else a,
               f"annotator {i}")
        for i, a in enumerate(annotators_obj)
    ]  # fmt: skip
    session = parse_line(SessionLine, session_obj, "session metadata")
    rounds = [parse_line(RoundLine, r, f"round {i}") for i, r in enumerate(rounds_obj)]
    plain = table.select([name for name in _SCHEMA.names if name in table.column_names])
    parsed = [
        parse_line(JudgementLine, {**row, "type": "judgement"}, f"row {i}")
        for i, row in enumerate(plain.to_pylist())
    ]
    judgements = [j for j in parsed if isinstance(j, JudgementLine)]
    assert isinstance(session, SessionLine)
    return SessionExport(
        session,
        tuple(r for r in rounds if isinstance(r, RoundLine)),
        tuple(judgements),
        states_of(_states_from_table(table, judgements)),
        tuple(a for a in annotators if isinstance(a, AnnotatorLine)),
    )
