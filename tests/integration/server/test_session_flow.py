"""The app end to end on one live server: a full round with its events, export / import,
the pairwise baseline, and clips over real HTTP."""

import json
import socket
import threading
from urllib.parse import urlsplit

import httpx
import pytest
from tests.integration.server.conftest import (
    TINY_FLAGS,
    TINY_SETTINGS,
    Server,
    judgement,
    wait_until,
)

from groupwise.storage.sessions import round_directory


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    running = Server(tmp_path_factory.mktemp("flow") / "data", "--env", "GridWorld", *TINY_FLAGS)
    running.start()
    yield running
    running.stop()


class Events(threading.Thread):
    """Reads a session's event stream into `events` [(name, data)] until stopped."""

    def __init__(self, url: str) -> None:
        super().__init__(daemon=True)
        self.url = url
        self.events: list[tuple[str, dict]] = []
        self.connected = threading.Event()
        self.stopped = False

    def run(self) -> None:
        name = None
        try:
            with httpx.stream("GET", self.url, timeout=httpx.Timeout(10, read=60)) as response:
                assert response.headers["content-type"].startswith("text/event-stream")
                self.connected.set()
                for line in response.iter_lines():
                    if self.stopped:
                        return
                    if line.startswith("event: "):
                        name = line[7:]
                    elif line.startswith("data: ") and name:
                        self.events.append((name, json.loads(line[6:])))
                        name = None
        except httpx.HTTPError:
            return

    def named(self, name: str) -> list[dict]:
        return [data for event, data in self.events if event == name]


def new_session(server: Server, mode: str = "groupwise") -> str:
    settings = {
        **TINY_SETTINGS,
        "pool_size": 16,
        "fragment_length": 10,
        "ppo_steps_per_round": 256,
        "round_seconds": 0,
        "comparisons_per_round": 0,
    }
    response = httpx.post(
        f"{server.url}/api/sessions",
        json={"env": "GridWorld", "mode": mode, "settings": settings},
        timeout=30,
    )
    assert response.status_code == 201, response.text
    return response.json()["id"]


def test_a_full_round_with_its_events(server):
    sid = server.session
    server.wait_for("ready", 0)
    events = Events(f"{server.url}/api/sessions/{sid}/events")
    events.start()
    assert events.connected.wait(30)
    with server.client() as http:
        url = f"/api/sessions/{sid}/judgements"
        first = judgement(0, ["b1", "b2"], ["b3"])
        stored = http.post(url, json=first)
        assert stored.status_code == 201
        retried = http.post(url, json=first)  # the page's retry after a lost answer
        assert retried.status_code == 200 and retried.json() == stored.json()
        assert (
            http.post(url, json=judgement(0, ["b4"], ["b5", "b6"], label="equal")).status_code
            == 201
        )
        mistake = http.post(url, json=judgement(0, ["b7"], ["b8"])).json()
        assert http.delete(f"{url}/{mistake['id']}").json()["undone"]

        # each change arrives; a store and an undo between two polls arrive as one event
        def latest() -> dict[str, dict]:
            return {j["client_id"]: j for j in events.named("judgement")}

        wait_until(lambda: latest().get(mistake["client_id"], {}).get("undone"), timeout=30)
        received = latest()
        assert len(received) == 3 and first["client_id"] in received
        assert received[first["client_id"]]["pairs"] == stored.json()["pairs"]
        assert received[mistake["client_id"]]["pairs"] == []

        state = http.post(f"/api/sessions/{sid}/end-round").json()
        assert state["phase"] == "training"
        state = server.wait_for("ready", 1)
        assert state["counts"]["comparisons_total"] == 2
        assert state["counts"]["pairs_total"] == 4
        assert wait_until(lambda: events.named("round"), timeout=30)[-1] == {"round": 1}
        phases = [s["phase"] for s in events.named("state")]
        # the stream sends the state as it is at each poll (~4 a second), so a training phase
        # shorter than a poll may not appear in it; the end-round answer above showed it
        assert phases[-1] == "ready"
        assert http.get(f"/api/sessions/{sid}/rounds/1/tree").status_code == 200
    events.stopped = True
    checkpoint = server.data / "sessions" / sid / "checkpoints" / "round-0000"
    # the job opens round 1 first (cut from the latest rollouts), then commits round 0
    assert wait_until(
        lambda: (checkpoint / "policy.zip").is_file() and (checkpoint / "reward.pt").is_file(),
        timeout=60,
    )
    manifest = json.loads((server.data / round_directory(sid, 0) / "pool.json").read_text())
    assert manifest["config"]["oversample"] == 2.0  # 16 behaviours of 32 windows, as sampled


def test_export_import_round_trip_over_http(server):
    sid = new_session(server)
    server.wait_for("ready", 0, session=sid)
    with server.client() as http:
        for body in (judgement(0, ["b1", "b2", "b3"], ["b4"]), judgement(0, ["b5"], ["b6"])):
            assert http.post(f"/api/sessions/{sid}/judgements", json=body).status_code == 201
        original = http.get(f"/api/sessions/{sid}/judgements").json()
        for fmt in ("jsonl", "parquet"):
            exported = http.get(f"/api/sessions/{sid}/export", params={"format": fmt})
            assert exported.status_code == 200
            imported = http.post(
                "/api/sessions/import",
                content=exported.content,
                headers={"content-type": exported.headers["content-type"]},
            )
            assert imported.status_code == 201, imported.text
            copy = imported.json()
            assert copy["phase"] == "finished" and copy["origin"] == sid
            copied = http.get(f"/api/sessions/{copy['id']}/judgements").json()
            assert [{**j, "id": 0} for j in copied] == [{**j, "id": 0} for j in original]


def test_pairwise_gives_the_next_pair_and_the_following_one(server):
    sid = new_session(server, "pairwise")
    server.wait_for("ready", 0, session=sid)
    with server.client() as http:
        ahead = http.get(f"/api/sessions/{sid}/pairwise/next").json()
        pair, following = ahead["pair"], ahead["following"]
        assert pair and following and pair != following
        for query in (pair, following):
            for clip in (query["left_clip"], query["right_clip"]):
                assert http.get(f"/clips/{clip}").headers["content-type"] == "video/mp4"
        answer = judgement(0, [pair["left"]], [pair["right"]], source="pairwise")
        assert http.post(f"/api/sessions/{sid}/judgements", json=answer).status_code == 201
        assert http.get(f"/api/sessions/{sid}/pairwise/next").json()["pair"] == following


def _raw_get(url: str, path: str, headers: str = "") -> tuple[int, bytes]:
    """A GET sent byte for byte (httpx would normalise `..` away)."""
    parts = urlsplit(url)
    with socket.create_connection((parts.hostname, parts.port), timeout=10) as sock:
        request = (
            f"GET {path} HTTP/1.1\r\nHost: {parts.netloc}\r\n{headers}Connection: close\r\n\r\n"
        )
        sock.sendall(request.encode())
        data = b""
        while chunk := sock.recv(65536):
            data += chunk
    status = int(data.split(b" ", 2)[1])
    return status, data


@pytest.mark.parametrize(
    "path",
    [
        "/clips/..%2F..%2Fetc%2Fpasswd",
        "/clips/../groupwise.db",
        "/clips/..%2Fgroupwise.db",
        "/clips/%2e%2e/groupwise.db",
        "/clips/../../../../etc/passwd",
        "/clips//etc/passwd",
        "/clips/groupwise.db",
        "/clips/" + "f" * 64 + ".mp4",
    ],
)
def test_nothing_but_stored_clips_is_served(server, path):
    status, body = _raw_get(server.url, path)
    assert status == 404, body[:300]
    assert b"root:" not in body and b"SQLite" not in body


def test_clips_support_range_requests(server):
    tree = wait_until(
        lambda: httpx.get(f"{server.url}/api/sessions/{server.session}/rounds/0/tree").json()
    )
    node = tree["tree"]
    while node["children"]:
        node = node["children"][0]
    status, data = _raw_get(server.url, f"/clips/{node['clip']}", "Range: bytes=0-99\r\n")
    assert status == 206
    head, body = data.split(b"\r\n\r\n", 1)
    assert b"content-range: bytes 0-99/" in head.lower() and len(body) == 100


def test_requests_in_a_row_are_answered_on_one_kept_alive_connection(server):
    # Nagle's algorithm once held every answer back ~40 ms (the client's delayed ACK). That
    # is a time, measured by benchmarks/submit_latency.py (one client's p50); its cause, no
    # TCP_NODELAY on accepted connections, is checked in test_serve_command.py. Here, without
    # a clock: thirty requests one after another on one connection are all answered.
    with server.client() as http:
        clients = set()
        for _ in range(30):
            answer = http.get("/api/health")
            assert answer.status_code == 200
            clients.add(answer.extensions["network_stream"].get_extra_info("client_addr"))
    assert len(clients) == 1, clients  # the client's end of the one connection
