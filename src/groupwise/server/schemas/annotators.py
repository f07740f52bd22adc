"""The people teaching a session: the owner and annotators, their agreement, the caller."""

from pydantic import Field

from groupwise.server.schemas.base import In, Out


class AgreementOut(Out):
    """An annotator's agreement with the others on the preference pairs they share (the
    same unordered pair of a round's behaviours), docs/teams.md."""

    kappa: float | None = Field(
        description="Cohen's κ over the shared pairs; null when n = 0 (or when chance "
        "agreement is certain: both used one label throughout)"
    )
    share: float | None = Field(description="share of the n pairs labelled alike; null: n = 0")
    n: int = Field(description="the shared pairs the numbers rest on")


class ModelAgreementOut(Out):
    """An annotator's strict preferences against the reward model that chose each round's
    pool (rounds after round 0), docs/teams.md."""

    share: float | None = Field(description="share the model orders alike; null: n = 0")
    n: int


class AnnotatorOut(Out):
    """Someone teaching the session: the owner (id "owner") or an annotator."""

    id: str = Field(examples=["owner", "a-3f9c0b1d2e4a"])
    name: str
    comparisons: int = Field(description="their judgements, not undone, in all rounds")
    pairs: int = Field(description="the preference pairs of those judgements")
    shown_s: float = Field(
        description="seconds from their first showing of each round to its close (or now)"
    )
    agreement: AgreementOut
    model_agreement: ModelAgreementOut


class MeOut(Out):
    """Who the request's token makes the caller in this session."""

    id: str = Field(description='"owner" or the annotator\'s id')
    name: str
    owner: bool = Field(description="whether they may end rounds, change the session, share it")


class AnnotatorIn(In):
    name: str = Field(max_length=1000, description="1…100 characters, no control characters")


class AnnotatorCreated(Out):
    """A new annotator: their token is shown this once (the link carries it)."""

    id: str
    name: str
    token: str
    link: str = Field(description="the page for them: the app's URL ?session=…&token=…")
