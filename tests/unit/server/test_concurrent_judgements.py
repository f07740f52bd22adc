"""Several clients answering one round at once through the HTTP app, on SQLite and on
PostgreSQL: each comparison is sent by two clients together (a retry racing its original),
some are undone, then the round is ended and the comparisons sent after it are refused.
(tests/unit/storage/test_concurrency.py races the end against the answers.)"""

import threading

import numpy as np
from tests.unit.server.conftest import TINY

CLIENTS = 6
"""Threads; clients t and t + CLIENTS / 2 send the same comparisons (same client ids)."""
PER_CLIENT = 8
LAST_AFTER_END = 2
"""Each client's last comparisons are sent after the round was ended (so they are refused)."""


def comparisons(plan: int) -> list[dict]:
    rng = np.random.default_rng([21, plan])
    bodies = []
    for k in range(PER_CLIENT):
        m, n = (int(x) for x in rng.integers(1, 4, size=2))
        picked = [f"b{i}" for i in rng.choice(TINY["pool_size"], size=m + n, replace=False)]
        bodies.append(
            {
                "client_id": f"plan{plan}-{k}",
                "round": 0,
                "left": picked[:m],
                "right": picked[m:],
                "label": str(rng.choice(["left", "right", "equal"])),
                "source": "explored",
            }
        )
    return bodies


def test_concurrent_clients_keep_every_invariant(prepared):
    client, sid, _ = prepared
    plans = CLIENTS // 2
    start = threading.Barrier(CLIENTS)
    ended = threading.Event()
    arrived = threading.Barrier(CLIENTS, action=lambda: _end_round(client, sid, ended))
    answers: list[list[tuple[str, int, int]]] = [[] for _ in range(CLIENTS)]
    undone: list[int] = []
    errors: list[BaseException] = []

    def run(thread: int) -> None:
        try:
            start.wait()
            for k, body in enumerate(comparisons(thread % plans)):
                if k == PER_CLIENT - LAST_AFTER_END:
                    arrived.wait()
                response = client.post(f"/api/sessions/{sid}/judgements", json=body)
                stored = response.json().get("id", -1)
                answers[thread].append((body["client_id"], response.status_code, stored))
                if thread < plans and k % 3 == 0 and response.status_code in (200, 201):
                    gone = client.delete(f"/api/sessions/{sid}/judgements/{stored}")
                    assert gone.status_code == 200, gone.text
                    undone.append(stored)
        except BaseException as error:
            errors.append(error)
            start.abort()
            arrived.abort()

    threads = [threading.Thread(target=run, args=(t,)) for t in range(CLIENTS)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors, errors
    assert ended.is_set()

    stored = client.get(f"/api/sessions/{sid}/judgements?include_undone=true").json()
    by_client = {j["client_id"]: j for j in stored}
    assert len(by_client) == len(stored)  # one judgement per client id
    created = [c for a in answers for c, status, _ in a if status == 201]
    assert sorted(created) == sorted(by_client)  # each stored by exactly one answer 201
    for thread in answers:
        for client_id, status, judgement_id in thread:
            assert status in (200, 201, 409)
            if status == 409:  # after End round: the comparison was never stored
                assert client_id not in by_client
            else:
                assert by_client[client_id]["id"] == judgement_id
    late = {c for a in answers for c, status, _ in a[PER_CLIENT - LAST_AFTER_END :]}
    assert late and late.isdisjoint(by_client)  # sent after the end: refused
    assert {j["id"] for j in stored if j["undone"]} == set(undone)
    for j in stored:
        assert len(j["pairs"]) == (0 if j["undone"] else max(len(j["left"]), len(j["right"])))
    # the round is closed: an undo is refused, a retry still answered
    some = next(j for j in stored if not j["undone"])
    assert client.delete(f"/api/sessions/{sid}/judgements/{some['id']}").status_code == 409
    again = {k: some[k] for k in ("client_id", "round", "left", "right", "label", "source")}
    assert client.post(f"/api/sessions/{sid}/judgements", json=again).status_code == 200


def _end_round(client, sid: str, ended: threading.Event) -> None:
    response = client.post(f"/api/sessions/{sid}/end-round")
    assert response.status_code == 200, response.text
    ended.set()
