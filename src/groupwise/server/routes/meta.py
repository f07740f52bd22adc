"""Meta: the envs a session can use, and the server's health."""

from typing import Literal

from fastapi import APIRouter

from groupwise.clips.timing import default_clip_seconds
from groupwise.envs import ENVS, TARGET_ENVS, TARGETS, EnvEntry
from groupwise.server.deps import Context
from groupwise.server.routes import ERRORS
from groupwise.server.schemas.meta import EnvOut, Health, TargetOut

router = APIRouter(prefix="/api", tags=["meta"], responses=ERRORS)


@router.get("/envs")
def list_envs() -> list[EnvOut]:
    """The six groupwise envs, then the case studies' reward-free target envs; any
    registered Gymnasium id with a fixed horizon works too."""
    return [_env_out(entry, "env") for entry in ENVS.values()] + [
        _env_out(entry, "target") for entry in TARGET_ENVS.values()
    ]


@router.get("/health")
def health(context: Context) -> Health:
    """The server is up; the training workers' pids while they run."""
    supervisor = context.supervisor
    return Health(worker_pid=supervisor.worker_pid, worker_pids=supervisor.worker_pids)


_TARGETS_BY_ENV = {target.env: target for target in TARGETS.values()}


def _env_out(entry: EnvEntry, kind: Literal["env", "target"]) -> EnvOut:
    target = _TARGETS_BY_ENV.get(entry.name) if kind == "target" else None
    return EnvOut(
        name=entry.name,
        gym_id=entry.gym_id,
        kind=kind,
        horizon=entry.horizon,
        clip_seconds=default_clip_seconds(entry.name),
        description=entry.changes,
        target=None
        if target is None
        else TargetOut(
            name=target.name,
            base=target.base,
            unit=target.unit,
            threshold=target.threshold,
            stretch=target.stretch,
            success=target.success,
            description=target.description,
        ),
    )
