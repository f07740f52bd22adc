"""The training worker's jobs, run in this process on real pools, PPO and checkpoints."""

import json

import pytest
from tests.unit.server.conftest import context_of, new_session, run_worker_once

from groupwise.clips.render import RenderPool
from groupwise.worker import jobs
from groupwise.worker.job import job_of
from groupwise.worker.progress import JobProgress


@pytest.mark.parametrize(
    ("training", "next_phase"),
    # continuous: the training job opens the next round from the latest rollouts (here none:
    # it samples the policy) before it commits the round
    [("rounds", "preparing"), ("continuous", "ready")],
)
def test_a_round_without_judgements_still_trains(client, training, next_phase):
    sid = new_session(client, training=training)["id"]
    run_worker_once(client)
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    run_worker_once(client)
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"], state["error"]) == (next_phase, 1, None)
    data = context_of(client).data_dir
    checkpoint = data / "sessions" / sid / "checkpoints" / "round-0000"
    record = json.loads((checkpoint / "state.json").read_text())["records"][0]
    assert record["round"] == 0 and record["pairs_total"] == 0


def test_a_failing_job_fails_its_session_only_and_retry_recovers(client):
    broken = new_session(client)["id"]
    healthy = new_session(client)["id"]
    data = context_of(client).data_dir
    blocker = data / "sessions" / broken
    blocker.parent.mkdir(parents=True, exist_ok=True)
    blocker.write_text("a file where the session's directory should be")

    run_worker_once(client)  # the broken one waited longest
    failed = client.get(f"/api/sessions/{broken}").json()
    assert failed["phase"] == "failed"
    assert failed["error"].startswith("preparing round 0 failed: FileExistsError")
    assert failed["failed_phase"] == "preparing"  # the page's heading: could not be prepared
    run_worker_once(client)  # the worker goes on with the others
    assert client.get(f"/api/sessions/{healthy}").json()["phase"] == "ready"

    blocker.unlink()
    retried = client.post(f"/api/sessions/{broken}/retry").json()
    assert (retried["phase"], retried["failed_phase"]) == ("preparing", None)
    run_worker_once(client)
    assert client.get(f"/api/sessions/{broken}").json()["phase"] == "ready"


class _Reports:
    """A `ProgressReporter` that keeps every report instead of writing it."""

    def __init__(self) -> None:
        self.reports: list[tuple[str, float, str]] = []

    def report(self, phase: str, fraction: float, message: str, *, force: bool = False) -> None:
        self.reports.append((phase, fraction, message))


def test_preparing_a_round_reports_sampling_distances_and_clips_as_they_go(client):
    """The bar moves through the whole pool phase (issue 23: it sat at 5 % for 17-28 s)."""
    sid = new_session(client, pool_size=40)["id"]
    context = context_of(client)
    job = job_of(context.db, sid)
    assert job is not None
    recorded = _Reports()
    with RenderPool(0) as render:
        progress = JobProgress(recorded)  # type: ignore[arg-type]  # a reporter that records
        jobs.prepare(job, context.db, context.data_dir, render, progress)
    phases = [phase for phase, _, _ in recorded.reports]
    assert list(dict.fromkeys(phases)) == ["load", "sample", "dtw", "clips", "suggestions"]
    fractions = [fraction for _, fraction, _ in recorded.reports]
    assert fractions == sorted(fractions) and 0 < fractions[0] and fractions[-1] < 1
    distinct = {p: len({f for q, f, _ in recorded.reports if q == p}) for p in phases}
    assert distinct["sample"] >= 3 and distinct["clips"] >= 3 and distinct["dtw"] >= 2
    last = {phase: message for phase, _, message in recorded.reports}
    assert "780 / 780 pairs" in last["dtw"]
    assert last["clips"].startswith("rendering posters 40 / 40")
