"""A round's pool as the views need it: the tree, suggestion edges, group suggestions, and
the pairwise baseline's next pairs; with them, how the pool's clips play (`clip_timing`).

The tree and medoids come from the prepared pool's directory (`groupwise.pool.publish` layout),
read once per round and cached: a prepared pool never changes. Everything else is read from
the database on each request.
"""

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from groupwise.episodes.ids import behaviour_id
from groupwise.server.context import AppContext
from groupwise.server.schemas.pairwise import PairQuery, PairSkip, PairwiseNext
from groupwise.server.schemas.rounds import (
    ClipTiming,
    Edge,
    RoundTree,
    Suggestion,
    SuggestionOut,
    TreeNodeOut,
)
from groupwise.storage import ConflictError, Database, InvalidError, NotFoundError
from groupwise.storage import rounds as repo
from groupwise.storage.annotators import OWNER_CALLER, Caller, list_annotators
from groupwise.storage.models import RoundRow
from groupwise.storage.phases import READY, ROUND_PREPARING
from groupwise.storage.sessions import get_round, get_session, settings_of


def _prepared_round(db: Database, session_id: str, index: int) -> RoundRow:
    with db.read() as s:
        get_session(s, session_id)
        row = get_round(s, session_id, index)
    if row.phase == ROUND_PREPARING:
        raise ConflictError(f"round {index} is still being prepared")
    return row


def _pool_directory(context: AppContext, row: RoundRow) -> Path:
    """The round's pool directory; only ever inside the data directory (an imported
    session's export could name any path)."""
    root = context.data_dir.resolve()
    if row.pool_dir is None:
        raise NotFoundError(f"the pool of round {row.index} is not available")
    directory = (root / row.pool_dir).resolve()
    if not directory.is_relative_to(root) or not (directory / "tree.json").is_file():
        raise NotFoundError(f"the pool of round {row.index} is not available")
    return directory


def clip_timing(directory: Path) -> ClipTiming | None:
    """The clip timing a pool's ``pool.json`` records (None for pools from before it)."""
    try:
        clip = json.loads((directory / "pool.json").read_text()).get("clip")
        return ClipTiming.model_validate(clip) if clip else None
    except (OSError, ValueError):
        return None


def _node(obj: dict[str, Any]) -> TreeNodeOut:
    extra = obj.get("extra") or {}
    return TreeNodeOut(
        id=obj["id"],
        kind=obj["kind"],
        level=obj["level"],
        size=obj["size"],
        children=[_node(child) for child in obj["children"]],
        behaviour=obj.get("behaviour"),
        clip=extra.get("clip"),
        poster=extra.get("poster"),
    )


def _tree(
    context: AppContext, session_id: str, row: RoundRow
) -> tuple[TreeNodeOut, int, dict[str, list[str]]]:
    key = (session_id, row.index)
    with context.trees_lock:
        cached = context.trees.get(key)
    if cached is not None:
        return cached
    directory = _pool_directory(context, row)
    data = json.loads((directory / "tree.json").read_text())
    medoids_file = directory / "medoids.json"
    raw = json.loads(medoids_file.read_text()) if medoids_file.is_file() else {}
    medoids = {node: [behaviour_id(i) for i in members] for node, members in raw.items()}
    value = (_node(data["root"]), int(data["levels"]), medoids)
    with context.trees_lock:
        context.trees[key] = value
    return value


def round_tree(context: AppContext, session_id: str, index: int) -> RoundTree:
    """The tree view of round `index`. Raises NotFoundError, ConflictError (preparing)."""
    row = _prepared_round(context.db, session_id, index)
    tree, levels, medoids = _tree(context, session_id, row)
    with context.db.read() as s:
        compared = repo.compared(s, row)
    return RoundTree(
        round=index,
        levels=levels,
        clip=clip_timing(_pool_directory(context, row)),
        tree=tree,
        medoids=medoids,
        compared=compared,
    )


def round_edges(db: Database, session_id: str, index: int, k: int) -> list[Edge]:
    """The round's `k` best pairwise suggestion edges, best first."""
    row = _prepared_round(db, session_id, index)
    with db.read() as s:
        return [Edge(a=e.a, b=e.b, score=e.score) for e in repo.edges(s, row.id, k)]


def _lease_s(db: Database, session_id: str) -> float:
    """Seconds a query is leased to one person: the session's `lease_s` once it is shared
    with an annotator, else 0 (one person alone: nothing to lease, nothing written)."""
    with db.read() as s:
        session = get_session(s, session_id)
        return settings_of(session).lease_s if list_annotators(s, session_id) else 0.0


def next_suggestion(
    db: Database,
    session_id: str,
    index: int,
    exclude: Sequence[Sequence[str]] | None,
    caller: Caller = OWNER_CALLER,
) -> SuggestionOut:
    """The best unused group suggestion of the round for `caller`, skipping `exclude`
    (consecutive [left], [right] lists) and what is leased to others; in a shared session
    leased to `caller` (`storage.rounds.next_suggestion`). Raises InvalidError for an odd
    number of lists, ConflictError unless round `index` is the open one."""
    lists = list(exclude or [])
    if len(lists) % 2:
        raise InvalidError("exclude must hold pairs of lists: [left ids], [right ids], …")
    queries = [(lists[i], lists[i + 1]) for i in range(0, len(lists), 2)]
    row = _open_round(db, session_id, index)
    lease_s = _lease_s(db, session_id)
    with db.write() if lease_s > 0 else db.read() as s:
        found = repo.next_suggestion(s, row.id, queries, holder=caller.id, lease_s=lease_s)
        if found is None:
            return SuggestionOut(suggestion=None)
        return SuggestionOut(
            suggestion=Suggestion(
                id=found.id,
                left=list(found.left),
                right=list(found.right),
                left_node=found.left_node,
                right_node=found.right_node,
                score=found.score,
            )
        )


def _open_round(db: Database, session_id: str, index: int | None = None) -> RoundRow:
    """The session's open round; raises ConflictError when none is open or when `index` (if
    given) names another round, as `…/shown` does (docs/app.md)."""
    with db.read() as s:
        session = get_session(s, session_id)
        if session.phase != READY:
            raise ConflictError(f"session {session_id} is {session.phase}; no round is open")
        if index is not None and index != session.round:
            state = "closed" if index < session.round else "not open yet"
            raise ConflictError(f"round {index} is {state}; the open round is {session.round}")
        return get_round(s, session_id, session.round)


def pairwise_next(
    context: AppContext, session_id: str, caller: Caller = OWNER_CALLER
) -> PairwiseNext:
    """The pair to ask `caller` now and the one after it (the page preloads both clips);
    in a shared session the first is leased to them."""
    db = context.db
    row = _open_round(db, session_id)
    lease_s = _lease_s(db, session_id)
    with db.write() if lease_s > 0 else db.read() as s:
        queue = repo.pairwise_next(s, row.id, 2, holder=caller.id, lease_s=lease_s)
        clips = {b.name: b for b in repo.behaviours(s, row.id)}

    def query(entry: Any) -> PairQuery:
        left, right = clips[entry.a], clips[entry.b]
        return PairQuery(
            left=entry.a,
            right=entry.b,
            left_clip=left.clip,
            right_clip=right.clip,
            left_poster=left.poster,
            right_poster=right.poster,
        )

    pairs = [query(entry) for entry in queue]
    try:
        clip = clip_timing(_pool_directory(context, row))
    except NotFoundError:
        clip = None
    return PairwiseNext(
        pair=pairs[0] if pairs else None,
        following=pairs[1] if len(pairs) > 1 else None,
        clip=clip,
    )


def skip_pair(
    context: AppContext, session_id: str, skip: PairSkip, caller: Caller = OWNER_CALLER
) -> PairwiseNext:
    """Skip a pair of the open round's queue; the next pairs. Raises NotFoundError."""
    row = _open_round(context.db, session_id)
    with context.db.write() as s:
        repo.skip_pair(s, row.id, skip.left, skip.right)
    return pairwise_next(context, session_id, caller)
