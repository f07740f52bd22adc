"""What the fault harness's clients were told (`Ledger`), checked against what the database
holds (`audit`), read with plain SQL through SQLAlchemy, not through the app's repositories.

The same checks run on SQLite and PostgreSQL: the SQL is portable (the column names
``left`` and ``right`` are keywords in PostgreSQL, so they are quoted; the JSON columns,
text in SQLite and ``json`` in PostgreSQL, are typed as SQLAlchemy's `JSON`, which decodes
both), and the reads cannot write (SQLite opened with ``mode=ro``, PostgreSQL transactions
``READ ONLY``; `read_only`).
"""

import dataclasses
import threading
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sqlalchemy import JSON, Boolean, Engine, Float, create_engine, text
from sqlalchemy.engine import make_url
from sqlalchemy.pool import NullPool

LABELS = {"left": 1.0, "right": 0.0, "equal": 0.5}
"""A judgement's label → its pairs' P(a preferred), a from the left group."""


class Ledger:
    """Every judgement sent and every answer received (thread-safe)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.bodies: dict[str, dict[str, Any]] = {}
        self.acknowledged: set[str] = set()
        self.refused: dict[str, int] = {}
        self.doubtful: set[str] = set()
        self.retried_ok = 0
        self.server_errors: list[str] = []

    def sent(self, body: dict[str, Any]) -> None:
        with self._lock:
            self.bodies[body["client_id"]] = body

    def in_doubt(self, client_id: str) -> None:
        """A request for `client_id` got no answer (it may or may not be stored)."""
        with self._lock:
            self.doubtful.add(client_id)

    def answered(self, client_id: str, status: int, text: str) -> None:
        with self._lock:
            if 200 <= status < 300:
                self.acknowledged.add(client_id)
                self.retried_ok += status == 200
            else:
                self.refused[client_id] = status
            if status >= 500:
                self.server_errors.append(f"{status} for judgement {client_id}: {text[:200]}")

    def control(self, status: int, what: str, text: str) -> None:
        """An answer to one of the harness's own requests (only 5xx matter)."""
        if status >= 500:
            with self._lock:
                self.server_errors.append(f"{status} for {what}: {text[:200]}")


@dataclass(frozen=True)
class Audit:
    """The database against the ledger; the first five counts must be 0."""

    database: str  # the backend and its server's version, "postgresql 15.14"
    lost: int  # answered 2xx, not stored
    duplicated: int  # a client_id stored more than once
    half_stored: int  # a live judgement without its max(m, n) pairs, or pairs without one
    altered: int  # stored otherwise than sent (groups, round, label, pairs), or refused
    server_errors: int  # 5xx answers
    orphans: int  # worker processes alive after the last server stopped
    sent: int
    acknowledged: int
    stored: int
    stored_unanswered: int  # stored although its sender got no 2xx (killed in between)
    refused: int
    problems: tuple[str, ...]

    def with_orphans(self, orphans: int) -> "Audit":
        extra = (f"{orphans} worker processes outlived their server",) if orphans else ()
        return dataclasses.replace(self, orphans=orphans, problems=self.problems + extra)


JUDGEMENTS = text(
    'SELECT id, client_id, round_index, "left", "right", label, undone FROM judgements '
    "WHERE session_id = :session"
).columns(left=JSON, right=JSON, undone=Boolean)
PAIRS = text("SELECT judgement_id, a, b, label FROM pairs ORDER BY judgement_id, position").columns(
    label=Float
)


def read_only(url: str) -> Engine:
    """An engine on `url` that cannot change it (module docstring); dispose of it after use."""
    parsed = make_url(url)
    if parsed.get_backend_name() == "sqlite":
        path = Path(parsed.database or "").resolve()
        return create_engine(
            f"sqlite:///file:{path}?mode=ro&uri=true",
            poolclass=NullPool,
            connect_args={"timeout": 30},
        )
    return create_engine(url, poolclass=NullPool, execution_options={"postgresql_readonly": True})


def audit(url: str, session_id: str, ledger: Ledger) -> Audit:
    """Compare the session's judgements and pairs in the database at `url` (a SQLAlchemy
    URL, SQLite or PostgreSQL) with `ledger`."""
    engine = read_only(url)
    try:
        with engine.begin() as db:
            version = ".".join(map(str, db.dialect.server_version_info or ()))
            rows = db.execute(JUDGEMENTS, {"session": session_id}).all()
            pairs: dict[int, list[tuple[str, str, float]]] = {}
            for judgement_id, a, b, label in db.execute(PAIRS):
                pairs.setdefault(judgement_id, []).append((a, b, label))
    finally:
        engine.dispose()
    problems: list[str] = []
    counts = Counter(client_id for _, client_id, *_ in rows)
    duplicated = sum(n - 1 for n in counts.values() if n > 1)
    problems += [f"client_id {c} stored {n} times" for c, n in counts.items() if n > 1]
    ids = {row[0] for row in rows}
    orphan_pairs = [j for j in pairs if j not in ids]
    problems += [f"pairs of judgement {j}, which is not stored" for j in orphan_pairs]
    half, altered = len(orphan_pairs), 0
    for judgement_id, client_id, round_index, left, right, label, undone in rows:
        own = pairs.get(judgement_id, [])
        body = ledger.bodies.get(client_id)
        if undone:
            half += bool(own)
            continue
        if len(own) != max(len(left), len(right)):
            half += 1
            problems.append(f"judgement {client_id} has {len(own)} pairs, not max(m, n)")
        elif body is None:
            altered += 1
            problems.append(f"judgement {client_id} was never sent")
        elif (round_index, left, right, label) != (
            body["round"],
            body["left"],
            body["right"],
            body["label"],
        ) or any(a not in left or b not in right or p != LABELS[label] for a, b, p in own):
            altered += 1
            problems.append(f"judgement {client_id} differs from what was sent")
    stored = set(counts)
    lost = ledger.acknowledged - stored
    contradicted = stored & set(ledger.refused)  # a resend of a stored one is answered 200
    altered += len(contradicted)
    problems += [f"judgement {c} was refused but is stored" for c in sorted(contradicted)]
    problems += [f"judgement {c} was answered 2xx but is not stored" for c in sorted(lost)]
    problems += ledger.server_errors
    return Audit(
        database=f"{engine.dialect.name} {version}",
        lost=len(lost),
        duplicated=duplicated,
        half_stored=half,
        altered=altered,
        server_errors=len(ledger.server_errors),
        orphans=0,
        sent=len(ledger.bodies),
        acknowledged=len(ledger.acknowledged),
        stored=len(stored),
        stored_unanswered=len(stored - ledger.acknowledged),
        refused=len(ledger.refused),
        problems=tuple(problems),
    )
