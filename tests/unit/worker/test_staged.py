"""A continuous session's next round is prepared ahead while the person compares, so that
"End round" opens it as soon as the round is committed (`worker.live`, `jobs.stage_next`)."""

from tests.unit.server.conftest import context_of, new_session, post_judgement, run_worker_once

from groupwise.storage.sessions import get_round, round_directory
from groupwise.worker import jobs as jobs_module
from groupwise.worker.jobs import sampled_at
from groupwise.worker.offers import STAGED_FILE
from groupwise.worker.process import Worker


def test_end_round_opens_the_round_prepared_ahead(client):
    sid = new_session(client, training="continuous", stage_after_s=0)["id"]
    run_worker_once(client)  # round 0 ready
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    context = context_of(client)
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    assert worker.train_live()  # one slice: the first fit, a rollout, the next round staged
    published = worker.live._live[sid].staged
    assert published is not None
    published.result()  # its clips render on the staging thread while slices go on
    staged = context.data_dir / round_directory(sid, 1) / STAGED_FILE
    assert staged.is_file()
    # sampled from the policy after its first rollout (1 env × 32 steps): the pool's age
    assert sampled_at(staged.parent) == 32
    assert client.get(f"/api/sessions/{sid}").json()["round"] == 0  # not opened yet
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    assert worker.run_next()  # the training job: round 0 committed, round 1 opened
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"], state["error"]) == ("ready", 1, None)
    assert not staged.exists()
    tree = client.get(f"/api/sessions/{sid}/rounds/1/tree")
    assert tree.status_code == 200 and tree.json()["round"] == 1
    assert tree.json()["tree"]["size"] == 16
    assert not worker.run_next()  # no preparing job was needed


def _staged_session(client) -> tuple[str, Worker]:
    """A continuous session in round 0 with one judgement and round 1 prepared ahead."""
    sid = new_session(client, training="continuous", stage_after_s=0)["id"]
    run_worker_once(client)
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    context = context_of(client)
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    assert worker.train_live()  # round 1 sampled; it is published on the staging thread
    return sid, worker


def _round_stats(client, sid: str, round_index: int) -> dict | None:
    with context_of(client).db.read() as s:
        return get_round(s, sid, round_index).stats


def test_the_round_prepared_ahead_opens_before_the_round_is_committed(client, monkeypatch):
    sid, worker = _staged_session(client)
    seen = []
    original = jobs_module.end_round

    def end_round(*args, **kwargs):  # what the page sees while round 0 is fitted
        state = client.get(f"/api/sessions/{sid}").json()
        seen.append((state["phase"], state["round"], _round_stats(client, sid, 0)))
        return original(*args, **kwargs)

    monkeypatch.setattr(jobs_module, "end_round", end_round)
    client.post(f"/api/sessions/{sid}/end-round")
    assert worker.run_next()
    assert seen == [("ready", 1, None)]
    stats = _round_stats(client, sid, 0)
    assert stats is not None and stats["pairs_total"] == 2  # max(m, n) pairs of 2 vs 1
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"]) == ("ready", 1)


def test_a_worker_killed_between_opening_and_committing_commits_on_resume(client):
    sid, worker = _staged_session(client)
    client.post(f"/api/sessions/{sid}/end-round")
    context = context_of(client)
    job = jobs_module.job_of(context.db, sid)
    assert job is not None
    training = worker.live.take(job)  # as the training job: round 1 is published by now
    assert jobs_module.open_staged(job, context.db, context.data_dir)
    training.run.close()  # killed here: round 1 open, round 0 not committed
    assert _round_stats(client, sid, 0) is None

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
    job = jobs_module.job_of(context.db, sid)
    assert job is not None
    training = worker.live.take(job)
    assert jobs_module.open_staged(job, context.db, context.data_dir)
    record = jobs_module.commit_round(job, context.db, context.data_dir, None, training)
    assert record.env_steps > 0 and _round_stats(client, sid, 0) is None  # killed here

    resumed = Worker(context.db, context.data_dir, poll_s=0.1)
    assert resumed.train_live()
    assert _round_stats(client, sid, 0) == record.stats()
