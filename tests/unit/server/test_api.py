"""The HTTP contract of docs/app.md, in-process on a real database and a real prepared pool."""

import uuid

import pytest
from tests.unit.server.conftest import new_session, run_worker_once


def judge(client, sid, left, right, label="left", client_id=None, round_index=0, **extra):
    body = {
        "client_id": client_id or str(uuid.uuid4()),
        "round": round_index,
        "left": left,
        "right": right,
        "label": label,
        "source": "explored",
        **extra,
    }
    return client.post(f"/api/sessions/{sid}/judgements", json=body)


def leaves(node: dict) -> list[dict]:
    if node["kind"] == "leaf":
        return [node]
    return [leaf for child in node["children"] for leaf in leaves(child)]


def test_envs_and_health(client):
    assert "GridWorld" in [env["name"] for env in client.get("/api/envs").json()]
    health = client.get("/api/health").json()
    assert health == {"status": "ok", "worker_pid": None, "worker_pids": []}


def test_a_new_session_waits_for_its_first_pool(client):
    state = new_session(client)
    assert (state["phase"], state["round"], state["rounds"]) == ("preparing", 0, 2)
    assert state["settings"]["pool_size"] == 16
    assert state["counts"] == {
        "comparisons_round": 0,
        "pairs_round": 0,
        "comparisons_total": 0,
        "pairs_total": 0,
    }
    assert client.get(f"/api/sessions/{state['id']}").json()["id"] == state["id"]
    assert [s["id"] for s in client.get("/api/sessions").json()] == [state["id"]]
    tree = client.get(f"/api/sessions/{state['id']}/rounds/0/tree")
    assert tree.status_code == 409 and "being prepared" in tree.json()["detail"]


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"env": "GridWorld", "settings": {"pool_size": 5000}}, "settings.pool_size"),
        ({"env": "GridWorld", "settings": {"fragment_length": 2}}, "settings.fragment_length"),
        ({"env": "GridWorld", "settings": {"clip_seconds": 0}}, "settings.clip_seconds"),
        ({"env": "Hopper", "settings": {"clip_seconds": 20}}, "horizon"),  # 2500 steps
        ({"env": "Hopper", "settings": {"fragment_length": 30, "clip_seconds": 1}}, "disagree"),
        ({"env": "GridWorld", "settings": {"colour": "red"}}, "settings.colour"),
        ({"env": "GridWorld", "mode": "psychic"}, "mode"),
        ({"env": "NoSuchEnv"}, "NoSuchEnv"),
        (
            {
                "env": "GridWorld",
                "settings": {"research": {"ppo": {"n_envs": 1, "n_steps": 8, "batch_size": 64}}},
            },
            "batch_size",
        ),
    ],
)
def test_bad_settings_are_422_with_one_sentence(client, body, field):
    response = client.post("/api/sessions", json=body)
    assert response.status_code == 422
    detail = response.json()["detail"]
    assert isinstance(detail, str) and field in detail


def test_unknown_things_are_404(client):
    assert client.get("/api/sessions/s-nope").status_code == 404
    assert client.get("/api/sessions/s-nope/events").status_code == 404
    assert client.delete("/api/sessions/s-nope/judgements/3").status_code == 404
    assert client.get("/api/nothing-here").status_code == 404


def test_the_round_tree_has_every_behaviour_with_its_clip(prepared):
    client, sid, _ = prepared
    tree = client.get(f"/api/sessions/{sid}/rounds/0/tree").json()
    found = leaves(tree["tree"])
    assert sorted(leaf["id"] for leaf in found) == sorted(f"b{i}" for i in range(16))
    assert all(leaf["id"] == f"b{leaf['behaviour']}" for leaf in found)
    assert all(leaf["clip"].endswith(".mp4") and leaf["poster"].endswith(".jpg") for leaf in found)
    assert tree["tree"]["id"] == "root" and tree["tree"]["level"] == tree["levels"]
    assert all(set(m) <= {leaf["id"] for leaf in found} for m in tree["medoids"].values())
    assert "true_return" not in str(tree)
    clip = client.get(f"/clips/{found[0]['clip']}")
    assert clip.status_code == 200 and clip.headers["content-type"] == "video/mp4"


def test_the_round_and_the_pairs_say_how_their_clips_play(prepared):
    client, groupwise, pairwise = prepared
    # GridWorld runs at 30 steps a second: L = 10 steps are 1/3 s, a frame per step
    expected = {"steps": 10, "stride": 1, "frames": 10, "fps": 30.0, "speed": 1.0}
    tree = client.get(f"/api/sessions/{groupwise}/rounds/0/tree").json()
    assert expected.items() <= tree["clip"].items()
    assert tree["clip"]["seconds"] == pytest.approx(1 / 3, abs=1e-6)
    pairs = client.get(f"/api/sessions/{pairwise}/pairwise/next").json()
    assert pairs["clip"] == tree["clip"]


def test_a_new_session_stores_its_behaviours_length_in_steps(client):
    hopper = client.post("/api/sessions", json={"env": "Hopper"}).json()
    assert hopper["settings"]["fragment_length"] == 188  # the env's 1.5 s of 0.008 s steps
    assert hopper["settings"]["clip_seconds"] == 1.5
    longer = client.post("/api/sessions", json={"env": "Hopper", "settings": {"clip_seconds": 2}})
    assert longer.json()["settings"]["fragment_length"] == 250
    steps = client.post(
        "/api/sessions", json={"env": "Hopper", "settings": {"fragment_length": 30}}
    )
    assert (
        steps.json()["settings"]["fragment_length"],
        steps.json()["settings"]["clip_seconds"],
    ) == (
        30,
        None,
    )


def test_edges_are_the_best_pairs_scaled_into_0_1(prepared):
    client, sid, _ = prepared
    edges = client.get(f"/api/sessions/{sid}/rounds/0/edges", params={"k": 5}).json()
    assert len(edges) == 5
    scores = [e["score"] for e in edges]
    assert scores == sorted(scores, reverse=True) and scores[0] == 1.0 and scores[-1] > 0


def test_next_suggestion_and_exclude(prepared):
    client, sid, _ = prepared
    url = f"/api/sessions/{sid}/rounds/0/next-suggestion"
    first = client.post(url).json()["suggestion"]
    assert first is not None and not set(first["left"]) & set(first["right"])
    assert 1 <= len(first["left"]) <= 8
    other = client.post(url, json={"exclude": [first["left"], first["right"]]}).json()
    assert other["suggestion"] != first
    odd = client.post(url, json={"exclude": [first["left"]]})
    assert odd.status_code == 422


def test_judgement_validation(prepared):
    client, sid, _ = prepared
    both = judge(client, sid, ["b1", "b2"], ["b2"])
    assert both.status_code == 422 and "both groups" in both.json()["detail"]
    assert judge(client, sid, [], ["b2"]).status_code == 422
    assert judge(client, sid, [f"b{i}" for i in range(9)], ["b15"]).status_code == 422
    unknown = judge(client, sid, ["b1"], ["b77"])
    assert unknown.status_code == 422
    assert unknown.json()["detail"] == "b77 is not a behaviour of round 0"
    assert judge(client, sid, ["x1"], ["b2"]).status_code == 422
    assert judge(client, sid, ["b1"], ["b2"], label="better").status_code == 422
    future = judge(client, sid, ["b1"], ["b2"], round_index=3)
    assert future.status_code == 409
    assert future.json()["detail"] == "round 3 is not open yet; the open round is 0"


def test_submit_retry_list_undo(prepared):
    client, sid, _ = prepared
    cid = str(uuid.uuid4())
    first = judge(client, sid, ["b3", "b4"], ["b5"], client_id=cid, seconds=3.5, edits=1)
    assert first.status_code == 201
    body = first.json()
    assert len(body["pairs"]) == 2 and body["seconds"] == 3.5 and not body["undone"]
    again = judge(client, sid, ["b3", "b4"], ["b5"], client_id=cid, seconds=3.5, edits=1)
    assert again.status_code == 200 and again.json() == body
    listed = client.get(f"/api/sessions/{sid}/judgements", params={"round": 0}).json()
    assert [j["client_id"] for j in listed].count(cid) == 1
    undone = client.delete(f"/api/sessions/{sid}/judgements/{body['id']}")
    assert undone.status_code == 200 and undone.json()["undone"] and undone.json()["pairs"] == []
    listed = client.get(f"/api/sessions/{sid}/judgements").json()
    assert cid not in [j["client_id"] for j in listed]


def test_pause_resume_and_timer(prepared):
    client, sid, _ = prepared
    client.post(f"/api/sessions/{sid}/rounds/0/shown")
    paused = client.post(f"/api/sessions/{sid}/pause").json()
    assert paused["timer"]["paused"] and not paused["timer"]["running"]
    assert client.get(f"/api/sessions/{sid}").json()["timer"] == paused["timer"]
    resumed = client.post(f"/api/sessions/{sid}/resume").json()
    assert not resumed["timer"]["paused"] and resumed["timer"]["running"]


def test_the_timer_starts_when_a_page_shows_the_round(client):
    sid = new_session(client)["id"]
    run_worker_once(client)
    opened = client.get(f"/api/sessions/{sid}").json()
    assert opened["phase"] == "ready"
    assert opened["timer"] == {
        "elapsed_s": 0.0,
        "budget_s": opened["settings"]["round_seconds"],
        "paused": False,
        "running": False,
        "shown_at": None,
    }
    shown = client.post(f"/api/sessions/{sid}/rounds/0/shown").json()
    assert shown["timer"]["running"] and shown["timer"]["shown_at"] is not None
    again = client.post(f"/api/sessions/{sid}/rounds/0/shown").json()
    assert again["timer"]["shown_at"] == shown["timer"]["shown_at"]
    later = client.post(f"/api/sessions/{sid}/rounds/1/shown")
    assert later.status_code == 409
    assert later.json()["detail"] == "round 1 is not open yet; the open round is 0"
    assert client.post("/api/sessions/s-000000000000/rounds/0/shown").status_code == 404


def test_pairwise_next_gives_the_pair_and_the_following_one(prepared):
    client, _, sid = prepared
    first = client.get(f"/api/sessions/{sid}/pairwise/next").json()
    pair, following = first["pair"], first["following"]
    assert pair and following and pair != following
    assert pair["left_clip"].endswith(".mp4") and pair["right_poster"].endswith(".jpg")
    grouped = judge(client, sid, ["b1", "b2"], ["b3"], source="pairwise")
    assert grouped.status_code == 422 and "at most 1" in grouped.json()["detail"]
    answered = judge(client, sid, [pair["left"]], [pair["right"]], source="pairwise")
    assert answered.status_code == 201
    assert client.get(f"/api/sessions/{sid}/pairwise/next").json()["pair"] == following
    skipped = client.post(
        f"/api/sessions/{sid}/pairwise/skip",
        json={"left": following["left"], "right": following["right"]},
    ).json()
    assert skipped["pair"] not in (pair, following)


def test_end_round_then_training_then_the_next_round(client):
    """Rounds training: the ended round trains, then the next one is prepared."""
    sid = new_session(client, training="rounds")["id"]
    run_worker_once(client)
    assert judge(client, sid, ["b1", "b2"], ["b3"]).status_code == 201
    ended = client.post(f"/api/sessions/{sid}/end-round").json()
    assert ended["phase"] == "training"
    assert client.post(f"/api/sessions/{sid}/end-round").status_code == 409
    assert judge(client, sid, ["b4"], ["b5"]).status_code == 409
    run_worker_once(client)  # train
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"]) == ("preparing", 1)
    run_worker_once(client)  # prepare round 1
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"]) == ("ready", 1)
    assert state["counts"]["comparisons_total"] == 1 and state["counts"]["comparisons_round"] == 0
    old = judge(client, sid, ["b1"], ["b2"])
    assert (
        old.status_code == 409 and old.json()["detail"] == "round 0 is closed; the open round is 1"
    )


def test_continuous_training_opens_the_next_round_with_the_ended_ones_training(client):
    """Continuous training: the job that commits the ended round cuts the next round's pool
    from PPO's latest rollouts and opens it (no preparing phase)."""
    sid = new_session(client, training="continuous")["id"]
    run_worker_once(client)
    assert judge(client, sid, ["b1", "b2"], ["b3"]).status_code == 201
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    run_worker_once(client)
    state = client.get(f"/api/sessions/{sid}").json()
    assert (state["phase"], state["round"]) == ("ready", 1)
    assert state["counts"]["comparisons_total"] == 1 and state["counts"]["comparisons_round"] == 0


def test_next_suggestion_is_409_for_any_round_but_the_open_one(client):
    sid = new_session(client)["id"]
    url = f"/api/sessions/{sid}/rounds/{{}}/next-suggestion"
    assert client.post(url.format(0)).status_code == 409  # round 0 is being prepared
    run_worker_once(client)
    assert client.post(url.format(0)).json()["suggestion"] is not None
    early = client.post(url.format(1))
    assert early.status_code == 409
    assert early.json()["detail"] == "round 1 is not open yet; the open round is 0"
    client.post(f"/api/sessions/{sid}/end-round")
    assert client.post(url.format(0)).status_code == 409  # training: no round is open
    while (state := client.get(f"/api/sessions/{sid}").json())["phase"] != "ready":
        assert state["phase"] in ("training", "preparing"), state
        run_worker_once(client)  # train, then prepare round 1
    closed = client.post(url.format(0))
    assert closed.status_code == 409
    assert closed.json()["detail"] == "round 0 is closed; the open round is 1"
    assert client.post(url.format(1)).json()["suggestion"] is not None


def test_export_and_import_over_http(prepared):
    client, sid, _ = prepared
    judge(client, sid, ["b6"], ["b7", "b8"], label="equal")
    for fmt, media_type in (
        ("jsonl", "application/x-ndjson"),
        ("parquet", "application/vnd.apache.parquet"),
    ):
        exported = client.get(f"/api/sessions/{sid}/export", params={"format": fmt})
        assert exported.status_code == 200
        assert exported.headers["content-type"].startswith(media_type)
        imported = client.post(
            "/api/sessions/import", content=exported.content, headers={"content-type": media_type}
        )
        assert imported.status_code == 201, imported.text
        state = imported.json()
        assert state["phase"] == "finished" and state["origin"] == sid
        original = client.get(f"/api/sessions/{sid}/judgements").json()
        copied = client.get(f"/api/sessions/{state['id']}/judgements").json()
        strip = lambda js: [{k: v for k, v in j.items() if k != "id"} for j in js]  # noqa: E731
        assert strip(copied) == strip(original)
    refused = client.post(
        "/api/sessions/import", content=b"a=b", headers={"content-type": "text/plain"}
    )
    assert refused.status_code == 415
    bad = client.post(
        "/api/sessions/import", content=b"{]", headers={"content-type": "application/x-ndjson"}
    )
    assert bad.status_code == 422 and "line 1" in bad.json()["detail"]
