"""Judgements: submit (idempotent on client_id), list, undo; each the caller's own."""

from typing import Annotated

from fastapi import APIRouter, Path, Query, Response, status

from groupwise.server import state
from groupwise.server.deps import Context, Me, SessionId
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.judgements import JudgementIn, JudgementOut
from groupwise.storage import judgements as repo
from groupwise.storage import judging
from groupwise.storage.annotators import Caller, display_names
from groupwise.storage.sessions import get_session

router = APIRouter(
    prefix="/api/sessions/{session_id}/judgements", tags=["judgements"], responses=ERRORS
)


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    responses={200: {"model": JudgementOut, "description": "a retry: the stored judgement"}},
)
def submit(
    session_id: SessionId, judgement: JudgementIn, context: Context, me: Me, response: Response
) -> JudgementOut:
    """Store the caller's judgement and its pairs (committed before this answer). A retry
    with the same client_id answers 200 with the stored judgement."""
    with context.db.write() as s:
        record, created = judging.add_judgement(s, session_id, _input(judgement, me))
        names = display_names(s, get_session(s, session_id))
    if not created:
        response.status_code = status.HTTP_200_OK
    return state.judgement_out(record, names)


def _input(judgement: JudgementIn, caller: Caller) -> judging.JudgementInput:
    return judging.JudgementInput(
        client_id=judgement.client_id,
        round=judgement.round,
        left=tuple(judgement.left),
        right=tuple(judgement.right),
        label=judgement.label,
        source=judgement.source,
        seconds=judgement.seconds,
        edits=judgement.edits,
        # the owner may name their judgements (the page's ?annotator=); an annotator's
        # carry their name, whatever the body says
        annotator=judgement.annotator if caller.is_owner else caller.name,
        annotator_id=caller.id,
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
        names = display_names(s, get_session(s, session_id))
    return [state.judgement_out(r, names) for r in records]


@router.delete("/{judgement_id}")
def undo(
    session_id: SessionId,
    judgement_id: Annotated[int, Path(ge=0, le=2**62)],
    context: Context,
    me: Me,
) -> JudgementOut:
    """Undo the caller's judgement of the open round (its pairs are removed); 403 for
    someone else's."""
    with context.db.write() as s:
        record = judging.undo_judgement(s, session_id, judgement_id, annotator_id=me.id)
        names = display_names(s, get_session(s, session_id))
    return state.judgement_out(record, names)
