"""The event stream of a session (``text/event-stream``, docs/app.md "Events").

One async generator per connection. It polls the session's `revision` about four times a
second on a worker thread (a read of one row, so streams never block other requests) and,
when it moved, sends:

- ``judgement``: each judgement stored or undone since the last revision sent
  (`JudgementOut`, with ``"undone": true`` for an undo), whoever made it: its
  ``annotator`` says who, its ``suggestion_id`` the suggestion it answered (a page drops
  that suggestion if it shows it);
- ``state``: the `SessionState` as the stream's viewer sees it, when phase, round,
  progress, counts, error, the timer's pause or the team's members and counts changed (not
  for the timer's ticking: the page counts seconds itself);
- ``round``: ``{"round": r}`` when round r has become ready (the page re-fetches);
- ``training``: each point of the learning curve the worker wrote since
  (`TrainingPointOut`, `groupwise.storage.training`).

Each event's ``id`` is the revision it reflects; a reconnecting EventSource sends it back
as ``Last-Event-ID`` and gets the judgements and training points it missed (in revision
order). On connect the stream sends the state at once; a quiet stream sends a keep-alive
comment every `keepalive_s`.
"""

import json
import time
from collections.abc import AsyncIterator
from typing import Any

import anyio
from pydantic import BaseModel

from groupwise.server.context import Viewer
from groupwise.server.schemas.rounds import RoundEvent
from groupwise.server.schemas.sessions import SessionState
from groupwise.server.state import close_if_due, judgement_out, read_state
from groupwise.server.training_views import point_out
from groupwise.storage import Database
from groupwise.storage.annotators import display_names
from groupwise.storage.judgements import list_judgements
from groupwise.storage.sessions import get_session
from groupwise.storage.training import list_points

RETRY_MS = 2000
"""How long a disconnected EventSource waits before it reconnects."""


def format_event(event: str, data: BaseModel | dict[str, Any], event_id: int | None) -> bytes:
    """One SSE message: ``event:``, optional ``id:``, one ``data:`` line of JSON."""
    payload = data.model_dump_json() if isinstance(data, BaseModel) else json.dumps(data)
    head = f"event: {event}\n" + (f"id: {event_id}\n" if event_id is not None else "")
    return f"{head}data: {payload}\n\n".encode()


def _key(state: SessionState) -> tuple[Any, ...]:
    return (
        state.phase,
        state.round,
        state.progress,
        state.counts,
        state.error,
        state.timer.paused,
        state.timer.running,
        tuple((a.id, a.name, a.comparisons, a.pairs) for a in state.annotators),
    )


async def session_events(
    db: Database,
    session_id: str,
    poll_s: float,
    keepalive_s: float,
    last_event_id: int | None = None,
    viewer: Viewer | None = None,
) -> AsyncIterator[bytes]:
    """The stream of one session as `viewer` sees it (module docstring). Ends when the
    client disconnects."""
    revision = await anyio.to_thread.run_sync(close_if_due, db, session_id)
    state = await anyio.to_thread.run_sync(read_state, db, session_id, viewer)
    yield f"retry: {RETRY_MS}\n\n".encode()
    yield format_event("state", state, revision)
    sent_judgements = last_event_id if last_event_id is not None else revision
    sent_points = sent_judgements
    if last_event_id is not None:
        chunks, sent_judgements = await _judgements(db, session_id, sent_judgements)
        points, sent_points = await _points(db, session_id, sent_points)
        for _, chunk in sorted(chunks + points, key=lambda c: c[0]):
            yield chunk
    key = _key(state)
    ready_round = state.round if state.phase == "ready" else None
    quiet_since = time.monotonic()
    while True:
        await anyio.sleep(poll_s)
        now_revision = await anyio.to_thread.run_sync(close_if_due, db, session_id)
        if now_revision == revision:
            if time.monotonic() - quiet_since >= keepalive_s:
                quiet_since = time.monotonic()
                yield b": keep-alive\n\n"
            continue
        chunks, sent_judgements = await _judgements(db, session_id, sent_judgements)
        points, sent_points = await _points(db, session_id, sent_points)
        for _, chunk in sorted(chunks + points, key=lambda c: c[0]):
            yield chunk
        revision = now_revision
        state = await anyio.to_thread.run_sync(read_state, db, session_id, viewer)
        if _key(state) != key:
            key = _key(state)
            yield format_event("state", state, revision)
        if state.phase == "ready" and state.round != ready_round:
            ready_round = state.round
            yield format_event("round", RoundEvent(round=state.round), revision)
        quiet_since = time.monotonic()


Chunks = list[tuple[int, bytes]]
"""Events with their revisions."""


async def _judgements(db: Database, session_id: str, after: int) -> tuple[Chunks, int]:
    """The events of judgements changed after revision `after`, and the newest revision
    among them (`after` when none)."""

    def read() -> tuple[Chunks, int]:
        with db.read() as s:
            records = list_judgements(s, session_id, include_undone=True, after_revision=after)
            names = display_names(s, get_session(s, session_id)) if records else {}
        chunks = [
            (r.revision, format_event("judgement", judgement_out(r, names), r.revision))
            for r in records
        ]
        return chunks, max([after, *(r.revision for r in records)])

    return await anyio.to_thread.run_sync(read)


async def _points(db: Database, session_id: str, after: int) -> tuple[Chunks, int]:
    """The events of training points written after revision `after`, and the newest
    revision among them (`after` when none)."""

    def read() -> tuple[Chunks, int]:
        with db.read() as s:
            points = list_points(s, session_id, after_revision=after)
        chunks = [(p.revision, format_event("training", point_out(p), p.revision)) for p in points]
        return chunks, max([after, *(p.revision for p in points)])

    return await anyio.to_thread.run_sync(read)
