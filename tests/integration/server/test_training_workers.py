"""`groupwise serve --training-workers 2`: two worker processes, each preparing and training
the sessions of its shard, so two sessions' continuous rounds train on two cores."""

import httpx
import pytest
from tests.integration.server.conftest import TINY_FLAGS, TINY_SETTINGS, judgement, wait_until

from groupwise.worker.process import shard_of


@pytest.mark.slow  # two workers training side by side (40 s); make test-slow runs it
def test_two_training_workers_serve_the_sessions_of_their_shards(serve):
    server = serve(
        "--env", "GridWorld", *TINY_FLAGS, "--training-workers", "2", settings=TINY_SETTINGS
    )
    sessions = {shard_of(server.session, 2): server.session}
    with server.client() as http:
        while len(sessions) < 2:  # a session in the other shard
            body = {"env": "GridWorld", "settings": {**TINY_SETTINGS, "pool_size": 16}}
            sid = http.post("/api/sessions", json=body).json()["id"]
            sessions.setdefault(shard_of(sid, 2), sid)
        for sid in sessions.values():
            server.wait_for("ready", 0, session=sid)
            answer = http.post(
                f"/api/sessions/{sid}/judgements", json=judgement(0, ["b0", "b1"], ["b2"])
            )
            assert answer.status_code == 201, answer.text

        def trained(sid: str) -> bool:
            points = http.get(f"/api/sessions/{sid}/training").json()["points"]
            return any(p["ppo_steps"] > 0 for p in points)

        for sid in sessions.values():  # both train while their rounds are open
            wait_until(lambda sid=sid: trained(sid), timeout=120)
        pids = httpx.get(f"{server.url}/api/health").json()["worker_pids"]
        assert len(set(pids)) == 2
