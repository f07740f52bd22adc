"""Meta: the envs a session can use, and the server's health."""

from fastapi import APIRouter

from groupwise.envs import ENVS, TARGET_ENVS
from groupwise.server.deps import Context
from groupwise.server.routes import ERRORS
from groupwise.server.schemas import Health

router = APIRouter(prefix="/api", tags=["meta"], responses=ERRORS)


@router.get("/envs")
def list_envs() -> list[str]:
    """The short env names, the case studies' reward-free target envs last; any registered
    Gymnasium id with a fixed horizon works too."""
    return [*ENVS, *TARGET_ENVS]


@router.get("/health")
def health(context: Context) -> Health:
    """The server is up; the training worker's pid while it runs (None otherwise)."""
    return Health(worker_pid=context.supervisor.worker_pid)
