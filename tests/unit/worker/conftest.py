"""The worker's tests use the app in-process (`tests.unit.server.conftest`)."""

from typing import Any

from tests.unit.server.conftest import (
    client,
    context_of,
    new_session,
    post_judgement,
    prepared,
    run_worker_once,
)

from groupwise.worker.process import Worker

__all__ = ["client", "prepared", "training_session"]


def training_session(client: Any, slices: int, **settings: Any) -> tuple[str, Worker]:
    """A continuous session in round 0 with one judgement, its worker trained `slices`
    rollouts."""
    sid = new_session(client, training="continuous", **settings)["id"]
    run_worker_once(client)  # round 0 ready
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    context = context_of(client)
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    for _ in range(slices):
        assert worker.train_continuous()
    return sid, worker
