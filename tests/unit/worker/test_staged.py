"""A continuous session's next round is prepared ahead while the person compares
(`worker.live`, `jobs.stage_next`) and waits in the database (`storage.staging`): the
round's end opens it in the same transaction, and the worker commits the ended round after."""

import dataclasses
import threading

from tests.unit.server.conftest import context_of, new_session, post_judgement, run_worker_once

from groupwise.storage.sessions import get_round
from groupwise.storage.staging import staged_rounds
from groupwise.worker import jobs as jobs_module
from groupwise.worker.jobs import sampled_at
from groupwise.worker.process import Worker


def _staged_session(client, **settings) -> tuple[str, Worker]:
    """A continuous session in round 0 with one judgement and round 1 staged."""
    sid = new_session(client, training="continuous", stage_after_s=0, **settings)["id"]
    run_worker_once(client)  # round 0 ready
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    context = context_of(client)
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    assert worker.train_live()  # one slice: the first fit, a rollout, round 1 sampled
    published = worker.live._live[sid].staged
    assert published is not None
    published.result()  # its clips render on the staging thread while slices go on
    return sid, worker


def _staged(client, sid: str) -> list[int]:
    with context_of(client).db.read() as s:
        return staged_rounds(s, sid)


def _round_stats(client, sid: str, round_index: int) -> dict | None:
    with context_of(client).db.read() as s:
        return get_round(s, sid, round_index).stats


def test_end_round_answers_with_the_round_prepared_ahead(client):
    sid, worker = _staged_session(client)
    assert _staged(client, sid) == [1]
    context = context_of(client)
    assert client.get(f"/api/sessions/{sid}").json()["round"] == 0  # not opened yet
    state = client.post(f"/api/sessions/{sid}/end-round").json()
    assert (state["phase"], state["round"], state["error"]) == ("ready", 1, None)
    assert _staged(client, sid) == []
    tree = client.get(f"/api/sessions/{sid}/rounds/1/tree")
    assert tree.status_code == 200 and tree.json()["tree"]["size"] == 16
    with context.db.read() as s:
        directory = context.data_dir / str(get_round(s, sid, 1).pool_dir)
    # sampled from the snapshot after its first rollout (1 env × 32 steps): the pool's age
    assert sampled_at(directory) == 32
    assert _round_stats(client, sid, 0) is None  # committed by the worker, after
    assert not worker.run_next()  # no training or preparing job is waiting
    assert worker.train_live()  # round 0 committed on the run that trained, then round 1
    stats = _round_stats(client, sid, 0)
    assert stats is not None and stats["pairs_total"] == 2  # max(m, n) pairs of 2 vs 1
    assert stats["env_steps"] == 32  # the live run's steps: nothing trained again
    assert worker.live._live[sid].round == 1


def test_a_round_ended_by_its_budget_opens_the_staged_round(client):
    sid, _ = _staged_session(client, comparisons_per_round=2)
    post_judgement(client, sid, ["b3"], ["b4"])  # the budget's second comparison
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"]) == ("ready", 1)


def test_finish_now_does_not_open_the_staged_round(client):
    sid, _ = _staged_session(client, rounds=3)
    state = client.post(f"/api/sessions/{sid}/finish").json()
    assert (state["phase"], state["round"]) == ("training", 0)


def test_a_round_ended_while_its_successor_renders_opens_it_when_ready(client):
    """Ended before the staged offer reached the database: the round goes the rounds-mode
    way (phase training) and the training job opens the staged round once it is ready."""
    sid = new_session(client, training="continuous", stage_after_s=0)["id"]
    run_worker_once(client)
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    context = context_of(client)
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    release = threading.Event()
    worker.live._staging.submit(release.wait)  # the staging thread is busy
    assert worker.train_live()  # round 1 sampled; its publishing queues behind
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    release.set()
    assert worker.run_next()  # the training job waits for it, opens it, commits round 0
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"], state["error"]) == ("ready", 1, None)
    assert _round_stats(client, sid, 0) is not None
    assert not worker.run_next()  # no preparing job was needed


def test_a_worker_killed_between_opening_and_committing_commits_on_resume(client):
    sid, worker = _staged_session(client)
    client.post(f"/api/sessions/{sid}/end-round")  # round 1 open, round 0 not committed
    worker.live.close()  # killed here
    assert _round_stats(client, sid, 0) is None

    context = context_of(client)
    resumed = Worker(context.db, context.data_dir, poll_s=0.1)
    post_judgement(client, sid, ["b3"], ["b4", "b5"], round_index=1)
    assert resumed.train_live()  # commits round 0 first, then trains round 1
    stats = _round_stats(client, sid, 0)
    assert stats is not None and stats["round"] == 0
    checkpoint = context.data_dir / jobs_module.checkpoint_of(sid, 0)
    assert (checkpoint / "state.json").is_file()
    training = resumed.live._live[sid]
    assert training.round == 1 and len(training.run.dataset) > stats["pairs_total"]


def test_a_round_checkpointed_but_not_recorded_keeps_its_checkpoint_on_resume(client):
    """Killed after `end_round` wrote round 0's checkpoint (and dropped the live one) but
    before its record was stored: the resumed worker records it from the checkpoint instead
    of training round 0 again from round −1 (which would lose its PPO steps)."""
    sid, worker = _staged_session(client)
    client.post(f"/api/sessions/{sid}/end-round")
    context = context_of(client)
    (job,), _ = worker.live._continuous_sessions()  # round 1, open
    ended = dataclasses.replace(job, round=0, phase="training")
    training = worker.live._live[sid]
    record = jobs_module.commit_round(ended, context.db, context.data_dir, None, training)
    assert record.env_steps > 0 and _round_stats(client, sid, 0) is None  # killed here

    resumed = Worker(context.db, context.data_dir, poll_s=0.1)
    assert resumed.train_live()
    assert _round_stats(client, sid, 0) == record.stats()
