"""A continuous session's next round is prepared ahead while the person compares, so that
"End round" opens it as soon as the round is committed (`worker.live`, `jobs.stage_next`)."""

from tests.unit.server.conftest import context_of, new_session, post_judgement, run_worker_once

from groupwise.storage.sessions import round_directory
from groupwise.worker import live as live_module
from groupwise.worker.jobs import sampled_at
from groupwise.worker.offers import STAGED_FILE
from groupwise.worker.process import Worker


def test_end_round_opens_the_round_prepared_ahead(client, monkeypatch):
    monkeypatch.setattr(live_module, "STAGE_AFTER_S", 0.0)
    sid = new_session(client, training="continuous")["id"]
    run_worker_once(client)  # round 0 ready
    post_judgement(client, sid, ["b0", "b1"], ["b2"])
    context = context_of(client)
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    assert worker.train_live()  # one slice: the first fit, a rollout, the next round staged
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
