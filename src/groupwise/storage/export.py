"""A session to its export and an export to a new session: the database side of the
session export (its lines: `groupwise.storage.export_format`; its files, JSONL and Parquet:
`export_jsonl`, `export_parquet`).

Undone judgements are exported (flagged, without pairs): the export is the record of truth.
Importing creates a new, finished session holding the same judgements and pairs (pairs are
copied, not derived again) with `origin` naming the exported session.

Who made each judgement is exported by name (``annotator``) and id (``annotator_id``), and
the team's counters and agreement as annotator lines (`storage.team`, docs/teams.md). An
import keeps the attribution: each annotator of the export becomes a removed annotator of
the new session (a new id, no token); each round line lists when each person first showed
the round, so everyone's time shown is the same after an import (an export made before
these views were exported keeps only the owner's).

With states (`export_session(..., states=StatesExport(data_dir))`), the export also carries
the arrays of every behaviour a judgement compared, read from the round's pool
(`groupwise.storage.states`), and, when `true_rewards` allows, their true rewards. Importing
such an export into a data directory writes them to the new session's round directories,
so the session's pairs train a reward model there (`states.preference_dataset`) without
the original pools.
"""

from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession

from groupwise.episodes.ids import behaviour_index
from groupwise.preferences.judgement import LABELS as PAIR_LABELS
from groupwise.storage.annotators import OWNER, display_names
from groupwise.storage.errors import InvalidError
from groupwise.storage.export_format import (
    AgreementLine,
    AnnotatorLine,
    JudgementLine,
    ModelAgreementLine,
    PairLine,
    RoundLine,
    SessionExport,
    SessionLine,
    ViewLine,
)
from groupwise.storage.judgements import LABELS, SOURCES, JudgementRecord, list_judgements
from groupwise.storage.models import (
    AnnotatorRow,
    JudgementRow,
    PairRow,
    RoundRow,
    RoundViewRow,
    SessionRow,
    utcnow,
)
from groupwise.storage.phases import FINISHED, ROUND_CLOSED
from groupwise.storage.sessions import (
    MODES,
    get_session,
    new_session_id,
    round_directory,
    touch,
)
from groupwise.storage.settings import SessionSettings
from groupwise.storage.states import BehaviourStates, read_round_states, write_round_states
from groupwise.storage.team import ScoreSource, team_stats


@dataclass(frozen=True)
class StatesExport:
    """Export the judged behaviours' states, read from `data_dir`'s pools."""

    data_dir: Path
    """The data directory the session's pools (or imported states) live in."""
    true_rewards: bool = True
    """Include the env's true rewards (the HTTP export does only for a finished session:
    while it runs, the person answering must not see them)."""


def export_session(
    s: DbSession,
    session_id: str,
    states: StatesExport | None = None,
    scores: ScoreSource | None = None,
) -> SessionExport:
    """Everything the export holds of a session; with `states`, the compared behaviours'
    arrays too; `scores`: the reward model's predictions for the annotators' model
    agreement (None: not computed). Raises NotFoundError (also when a round's pool is
    gone)."""
    session = get_session(s, session_id)
    names = display_names(s, session)
    rounds = list(
        s.scalars(
            select(RoundRow).where(RoundRow.session_id == session_id).order_by(RoundRow.index)
        )
    )
    judgements = list_judgements(s, session_id, include_undone=True)
    views: dict[int, list[ViewLine]] = {}
    for view in s.scalars(
        select(RoundViewRow)
        .where(RoundViewRow.round_id.in_([r.id for r in rounds]))
        .order_by(RoundViewRow.id)
    ):
        line = ViewLine(annotator_id=view.annotator, shown_at=view.shown_at)
        views.setdefault(view.round_id, []).append(line)
    behaviours: tuple[BehaviourStates, ...] = ()
    if states is not None:
        behaviours = _judged_states(session_id, rounds, judgements, states)
    return SessionExport(
        session=SessionLine(
            id=session.id,
            env=session.env,
            mode=session.mode,  # type: ignore[arg-type]  # checked on creation (MODES)
            settings=SessionSettings.stored(session.settings),
            annotator=session.annotator,
            phase=session.phase,
            round=session.round,
            created_at=session.created_at,
        ),
        rounds=tuple(
            RoundLine(
                round=r.index,
                pool_dir=r.pool_dir,
                opened_at=r.opened_at,
                shown_at=r.shown_at,
                closed_at=r.closed_at,
                close_reason=r.close_reason,
                views=views.get(r.id, []),
            )
            for r in rounds
        ),
        judgements=tuple(
            JudgementLine(
                id=j.id,
                seq=j.seq,
                client_id=j.client_id,
                round=j.round,
                left=list(j.left),
                right=list(j.right),
                label=j.label,  # type: ignore[arg-type]  # validated on storing
                source=j.source,  # type: ignore[arg-type]  # validated on storing
                seconds=j.seconds,
                edits=j.edits,
                annotator=(j.annotator or names[OWNER])
                if j.annotator_id == OWNER
                else names.get(j.annotator_id, j.annotator),
                annotator_id=j.annotator_id,
                created_at=j.created_at,
                undone=j.undone,
                pairs=[PairLine(a=p.a, b=p.b, label=p.label) for p in j.pairs],
            )
            for j in judgements
        ),
        behaviours=behaviours,
        annotators=tuple(
            AnnotatorLine(
                id=a.id,
                name=a.name,
                comparisons=a.comparisons,
                pairs=a.pairs,
                shown_s=a.shown_s,
                agreement=AgreementLine(
                    kappa=a.agreement.kappa, share=a.agreement.share, n=a.agreement.n
                ),
                model_agreement=ModelAgreementLine(
                    share=a.model_agreement.share, n=a.model_agreement.n
                ),
                removed=a.removed,
            )
            for a in team_stats(s, session, scores=scores, include_removed=True)
        ),
    )


def _judged_states(
    session_id: str,
    rounds: list[RoundRow],
    judgements: list[JudgementRecord],
    states: StatesExport,
) -> tuple[BehaviourStates, ...]:
    """Per round with judgements, the states of every behaviour they compared."""
    found = []
    for row in rounds:
        names = {n for j in judgements if j.round == row.index for n in (*j.left, *j.right)}
        if not names:
            continue
        ordered = sorted(names, key=behaviour_index)
        read = read_round_states(states.data_dir, session_id, row.index, row.pool_dir, ordered)
        if not states.true_rewards:
            read = BehaviourStates(read.round, read.names, read.obs, read.acts, None)
        found.append(read)
    return tuple(found)


def import_session(
    s: DbSession,
    export: SessionExport,
    now: datetime | None = None,
    *,
    data_dir: Path | None = None,
) -> SessionRow:
    """Add a new, finished session holding the export's rounds, judgements and pairs; the
    export's states, if any, are written into `data_dir`'s round directories of the new
    session (before the caller commits).

    Raises InvalidError when the export contradicts itself (a judgement of a round that is
    not listed, a client_id or seq twice, an unknown mode, states that lack a compared
    behaviour) or carries states and no `data_dir` is given.
    """
    now = now or utcnow()
    meta = export.session
    _check_states(export)
    if export.behaviours and data_dir is None:
        raise InvalidError("the export carries states; import it into a data directory")
    if meta.mode not in MODES:
        raise InvalidError(f"mode must be one of {MODES}")
    indices = sorted({r.round for r in export.rounds} | {j.round for j in export.judgements})
    listed = {r.round: r for r in export.rounds}
    missing = sorted({j.round for j in export.judgements} - set(listed))
    if missing:
        raise InvalidError(f"judgements of round {missing[0]}, which the export does not list")
    for field in ("client_id", "seq"):
        values = [getattr(j, field) for j in export.judgements]
        if len(set(values)) != len(values):
            raise InvalidError(f"two judgements of the export share a {field}")
    for j in export.judgements:
        if j.label not in LABELS or j.source not in (*SOURCES, "simulated"):
            raise InvalidError(f"judgement {j.id} has an unknown label or source")
        if any(p.label not in PAIR_LABELS for p in j.pairs):
            raise InvalidError(f"a pair of judgement {j.id} has a label other than 0, 0.5, 1")
    session = SessionRow(
        id=new_session_id(),
        env=meta.env,
        mode=meta.mode,
        settings=meta.settings.model_dump(mode="json"),
        annotator=meta.annotator,
        phase=FINISHED,
        round=max(indices, default=0),
        progress_phase="finished",
        progress_fraction=1.0,
        progress_message=f"imported from {meta.id}",
        judgement_seq=max((j.seq + 1 for j in export.judgements), default=0),
        origin=meta.id,
        revision=0,
        created_at=now,
        updated_at=now,
    )
    s.add(session)
    touch(session, now)
    s.flush()
    people = _import_annotators(s, session.id, export, now)
    round_ids: dict[int, int] = {}
    for index in indices:
        line = listed[index]
        row = RoundRow(
            session_id=session.id,
            index=index,
            phase=ROUND_CLOSED,
            pool_dir=line.pool_dir,
            opened_at=line.opened_at,
            shown_at=line.shown_at,
            closed_at=line.closed_at,
            close_reason=line.close_reason,
        )
        s.add(row)
        s.flush()
        round_ids[index] = row.id
        # each person's first showing, so everyone's time shown survives (issue 40)
        first: dict[str, datetime] = {}
        for view in line.views:
            who = OWNER if view.annotator_id == OWNER else people.get(view.annotator_id)
            if who is not None:  # else someone the export lists neither as annotator nor maker
                first[who] = min(first.get(who, view.shown_at), view.shown_at)
        s.add_all(RoundViewRow(round_id=row.id, annotator=w, shown_at=t) for w, t in first.items())
    for j in export.judgements:
        s.add(
            JudgementRow(
                session_id=session.id,
                round_id=round_ids[j.round],
                round_index=j.round,
                seq=j.seq,
                client_id=j.client_id,
                left=list(j.left),
                right=list(j.right),
                label=j.label,
                source=j.source,
                seconds=j.seconds,
                edits=j.edits,
                annotator=j.annotator,
                annotator_id=people.get(j.annotator_id),
                created_at=j.created_at,
                undone=j.undone,
                undone_at=now if j.undone else None,
                revision=session.revision,
                pairs=[
                    PairRow(position=i, a=p.a, b=p.b, label=p.label)
                    for i, p in enumerate([] if j.undone else j.pairs)
                ],
            )
        )
    s.flush()
    if data_dir is not None:
        for states in export.behaviours:
            write_round_states(data_dir / round_directory(session.id, states.round), states)
    return session


def _import_annotators(
    s: DbSession, session_id: str, export: SessionExport, now: datetime
) -> dict[str, str]:
    """The export's annotators as removed annotators of the new session (no token): their
    id in the export → their new id (the owner stays the owner)."""
    named = {a.id: a.name for a in export.annotators}
    for j in export.judgements:
        named.setdefault(j.annotator_id, j.annotator or j.annotator_id)
    ids: dict[str, str] = {}
    for old, name in named.items():
        if old == OWNER:
            continue
        ids[old] = f"a-{new_session_id()[2:]}"
        s.add(
            AnnotatorRow(
                id=ids[old],
                session_id=session_id,
                name=name[:200],
                token_sha256=None,
                created_at=now,
                removed_at=now,
            )
        )
    s.flush()
    return ids


def _check_states(export: SessionExport) -> None:
    """An export with states holds every behaviour its judgements compared, once a round."""
    if not export.behaviours:
        return
    by_round = {states.round: states for states in export.behaviours}
    if len(by_round) != len(export.behaviours):
        raise InvalidError("the export lists the states of a round twice")
    for j in export.judgements:
        if j.round not in by_round:
            raise InvalidError(f"the export has no states of round {j.round}")
        for name in (*j.left, *j.right):
            by_round[j.round].row(name)
