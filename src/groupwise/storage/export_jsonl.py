"""The session export as JSONL, one JSON object a line (`export_format`'s docstring and
docs/export.md): writing it and parsing it."""

import json

from groupwise.storage.errors import InvalidError
from groupwise.storage.export_format import (
    AnnotatorLine,
    BehaviourLine,
    ExportLine,
    JudgementLine,
    RoundLine,
    SessionExport,
    SessionLine,
    parse_line,
    states_of,
)
from groupwise.storage.states import BehaviourStates


def to_jsonl(export: SessionExport) -> bytes:
    """The JSONL bytes of an export (`export_format`'s docstring)."""
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
    kinds: dict[str, type[ExportLine]] = {
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
        parsed = parse_line(kind, obj, f"line {number}")
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
        session, tuple(rounds), tuple(judgements), states_of(behaviours), tuple(annotators)
    )
