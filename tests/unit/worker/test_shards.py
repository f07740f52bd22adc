"""Several training workers (`serve --training-workers N`): each serves the sessions whose
id hashes to its shard (`process.shard_of`), and the supervisor keeps one process per shard
with work."""

from tests.unit.server.conftest import context_of, new_session, post_judgement

from groupwise.worker.process import Worker, shard_of
from groupwise.worker.supervisor import Supervisor, WorkerConfig


def test_shard_of_is_stable_and_spreads_sessions():
    ids = [f"s-{i:012x}" for i in range(400)]
    assert [shard_of(i, 3) for i in ids] == [shard_of(i, 3) for i in ids]
    counts = [sum(shard_of(i, 3) == k for i in ids) for k in range(3)]
    assert min(counts) > 100  # about a third each
    assert {shard_of(i, 1) for i in ids} == {0}


def _sessions_in_both_shards(client, **settings) -> dict[int, list[str]]:
    shards: dict[int, list[str]] = {0: [], 1: []}
    while not (shards[0] and shards[1]):
        sid = new_session(client, **settings)["id"]
        shards[shard_of(sid, 2)].append(sid)
    return shards


def _phase(client, sid: str) -> str:
    return client.get(f"/api/sessions/{sid}").json()["phase"]


def test_a_worker_runs_only_the_jobs_of_its_shard(client):
    shards = _sessions_in_both_shards(client)
    context = context_of(client)
    first = Worker(context.db, context.data_dir, poll_s=0.1, shard=(0, 2))
    while first.run_next():
        pass
    assert {_phase(client, sid) for sid in shards[0]} == {"ready"}
    assert {_phase(client, sid) for sid in shards[1]} == {"preparing"}
    second = Worker(context.db, context.data_dir, poll_s=0.1, shard=(1, 2))
    while second.run_next():
        pass
    assert {_phase(client, sid) for sid in shards[1]} == {"ready"}


def test_a_worker_trains_only_the_open_rounds_of_its_shard(client):
    shards = _sessions_in_both_shards(client, training="continuous")
    context = context_of(client)
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    while worker.run_next():  # every round 0 ready
        pass
    for sid in shards[0] + shards[1]:
        post_judgement(client, sid, ["b0", "b1"], ["b2"])
    second = Worker(context.db, context.data_dir, poll_s=0.1, shard=(1, 2))
    for _ in range(len(shards[1])):
        assert second.train_continuous()
    assert set(second.continuous._rounds) == set(shards[1])


def test_the_supervisor_starts_a_worker_per_shard_with_work(client):
    _sessions_in_both_shards(client)  # all preparing: work in both shards
    context = context_of(client)
    config = WorkerConfig(context.db.url, context.data_dir, processes=2)
    supervisor = Supervisor(context.db, config)
    try:
        supervisor.check()
        assert len(supervisor.worker_pids) == 2
    finally:
        supervisor.stop()
    assert supervisor.worker_pids == []
