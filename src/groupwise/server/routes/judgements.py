"""Judgements: submit (idempotent on client_id), list, undo."""

from typing import Annotated

from fastapi import APIRouter, Path, Query, Response, status

from groupwise.server import state
from groupwise.server.deps import Context, SessionId
from groupwise.server.routes import ERRORS
from groupwise.server.schemas import JudgementIn, JudgementOut
from groupwise.storage import judgements as repo

router = APIRouter(
    prefix="/api/sessions/{session_id}/judgements", tags=["judgements"], responses=ERRORS
)


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    responses={200: {"model": JudgementOut, "description": "a retry: the stored judgement"}},
)
def submit(
    session_id: SessionId, judgement: JudgementIn, context: Context, response: Response
) -> JudgementOut:
    """Store a judgement and its pairs (committed before this answer). A retry with the
    same client_id answers 200 with the stored judgement."""
    record, created = repo_add(context, session_id, judgement)
    if not created:
        response.status_code = status.HTTP_200_OK
    return state.judgement_out(record)


def repo_add(
    context: Context, session_id: str, judgement: JudgementIn
) -> tuple[repo.JudgementRecord, bool]:
    with context.db.write() as s:
        return repo.add_judgement(
            s,
            session_id,
            repo.JudgementInput(
                client_id=judgement.client_id,
                round=judgement.round,
                left=tuple(judgement.left),
                right=tuple(judgement.right),
                label=judgement.label,
                source=judgement.source,
                seconds=judgement.seconds,
                edits=judgement.edits,
                annotator=judgement.annotator,
            ),
        )


@router.get("")
def list_judgements(
    session_id: SessionId,
    context: Context,
    round: Annotated[int | None, Query(ge=0, le=10_000)] = None,
    include_undone: bool = False,
) -> list[JudgementOut]:
    """The session's judgements (of one round with ?round=), oldest first."""
    with context.db.read() as s:
        records = repo.list_judgements(s, session_id, round, include_undone=include_undone)
    return [state.judgement_out(r) for r in records]


@router.delete("/{judgement_id}")
def undo(
    session_id: SessionId,
    judgement_id: Annotated[int, Path(ge=0, le=2**62)],
    context: Context,
) -> JudgementOut:
    """Undo a judgement of the open round (its pairs are removed)."""
    with context.db.write() as s:
        record = repo.undo_judgement(s, session_id, judgement_id)
    return state.judgement_out(record)
