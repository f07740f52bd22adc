"""Several people teaching one agent through the HTTP app (docs/teams.md), on SQLite and
on PostgreSQL: the owner shares a session, each annotator acts with their own token, their
judgements and undos are theirs, suggestions and pairs are leased so two people do not get
the same one, the event stream says who answered what, and the owner's actions stay the
owner's."""

import dataclasses
import json
import threading
import uuid

import anyio
import pytest
from tests.unit.server.conftest import context_of, make_client
from tests.unit.storage.conftest import N, prepared

from groupwise.server.context import Viewer
from groupwise.server.events import session_events
from groupwise.storage import SessionSettings
from groupwise.storage import sessions as sessions_repo
from groupwise.storage.annotators import Caller
from groupwise.storage.rounds import GroupSuggestionInput, store_prepared_round

POOL = dataclasses.replace(
    prepared(),
    suggestions=(
        *prepared().suggestions,
        GroupSuggestionInput(("b7",), ("b8",), "m5", "m6", 0.5),
    ),
)
"""A hand-made pool: what the judgement, suggestion and pairwise routes need (no clips)."""


def open_session(client, mode: str = "groupwise", **settings) -> str:
    """A session whose round 0 is open on `POOL` (no worker needed)."""
    db = context_of(client).db
    with db.write() as s:
        settings = {"comparisons_per_round": 0, **settings}
        sid = sessions_repo.create_session(s, "GridWorld", mode, SessionSettings(**settings)).id
    with db.write() as s:
        assert store_prepared_round(s, sid, 0, POOL)
    return sid


def add(client, sid: str, name: str, **headers) -> dict:
    response = client.post(f"/api/sessions/{sid}/annotators", json={"name": name}, **headers)
    assert response.status_code == 201, response.text
    return response.json()


def bearer(who: dict) -> dict:
    return {"headers": {"Authorization": f"Bearer {who['token']}"}}


def body(left, right, label="left", source="explored", client_id=None) -> dict:
    return {
        "client_id": client_id or str(uuid.uuid4()),
        "round": 0,
        "left": left,
        "right": right,
        "label": label,
        "source": source,
    }


def test_the_owner_shares_a_session_and_each_annotator_acts_as_themselves(client):
    sid = open_session(client)
    ada = add(client, sid, "Ada")
    assert ada["name"] == "Ada" and ada["id"].startswith("a-")
    assert ada["link"] == f"http://testserver/?session={sid}&token={ada['token']}"

    owner_view = client.get(f"/api/sessions/{sid}").json()
    assert owner_view["me"] == {"id": "owner", "name": "owner", "owner": True}
    for how in (bearer(ada), {"params": {"token": ada["token"]}}):
        mine = client.get(f"/api/sessions/{sid}", **how).json()
        assert mine["me"] == {"id": ada["id"], "name": "Ada", "owner": False}
    team = client.get(f"/api/sessions/{sid}/annotators", **bearer(ada)).json()
    assert [(a["id"], a["name"], a["comparisons"]) for a in team] == [
        ("owner", "owner", 0), (ada["id"], "Ada", 0)
    ]  # fmt: skip
    assert team[1]["agreement"] == {"kappa": None, "share": None, "n": 0}
    assert team[1]["model_agreement"] == {"share": None, "n": 0}
    assert owner_view["annotators"] == team

    made = client.post(f"/api/sessions/{sid}/judgements", json=body(["b1"], ["b2"]), **bearer(ada))
    assert made.status_code == 201
    assert made.json()["annotator"] == {"id": ada["id"], "name": "Ada"}
    history = client.get(f"/api/sessions/{sid}/judgements").json()
    assert [j["annotator"] for j in history] == [{"id": ada["id"], "name": "Ada"}]
    shown = client.post(f"/api/sessions/{sid}/rounds/0/shown", **bearer(ada)).json()
    assert [a["comparisons"] for a in shown["annotators"]] == [0, 1]


@pytest.mark.parametrize(
    ("name", "status", "detail"),
    [
        ("ada", 409, "already has an annotator named 'ada'"),
        ("", 422, "must not be empty"),
        ("x" * 101, 422, "at most 100 characters"),
        ("Ada\tLovelace", 422, "control character U+0009"),
    ],
)
def test_annotator_names_are_refused_with_a_reason(client, name, status, detail):
    sid = open_session(client)
    add(client, sid, "Ada")
    response = client.post(f"/api/sessions/{sid}/annotators", json={"name": name})
    assert response.status_code == status
    assert detail in response.json()["detail"]


def test_an_annotator_may_not_do_what_only_the_owner_may(client):
    sid, other = open_session(client), open_session(client)
    ada = add(client, sid, "Ada")
    refused = {
        f"/api/sessions/{sid}/end-round": "end the round",
        f"/api/sessions/{sid}/pause": "pause the round",
        f"/api/sessions/{sid}/resume": "resume the round",
        f"/api/sessions/{sid}/retry": "retry a failed step",
        f"/api/sessions/{sid}/finish": "finish the session",
        f"/api/sessions/{sid}/annotators": "add annotators",
    }
    for path, action in refused.items():
        response = client.post(path, json={"name": "Eve"}, **bearer(ada))
        assert response.status_code == 403, path
        assert response.json()["detail"] == (
            f"only the session's owner can {action}; Ada is an annotator"
        )
    gone = client.delete(f"/api/sessions/{sid}/annotators/{ada['id']}", **bearer(ada))
    assert gone.status_code == 403
    cont = client.post(f"/api/sessions/{sid}/continue", json={"steps": 1}, **bearer(ada))
    assert cont.status_code == 403
    created = client.post("/api/sessions", json={"env": "GridWorld"}, **bearer(ada))
    assert created.status_code == 403
    assert "only the owner creates sessions" in created.json()["detail"]
    imported = client.post(
        "/api/sessions/import",
        content=b"{}",
        headers={"Authorization": f"Bearer {ada['token']}", "Content-Type": "application/x-ndjson"},
    )
    assert imported.status_code == 403
    elsewhere = client.get(f"/api/sessions/{other}", **bearer(ada))
    assert elsewhere.status_code == 403
    assert elsewhere.json()["detail"] == (
        f"Ada's token is for session {sid}; it does not reach session {other}"
    )
    assert client.get(f"/api/sessions/{other}/events", **bearer(ada)).status_code == 403
    listed = client.get("/api/sessions", **bearer(ada)).json()
    assert [s["id"] for s in listed] == [sid]
    assert {s["id"] for s in client.get("/api/sessions").json()} == {sid, other}
    assert client.post(f"/api/sessions/{sid}/end-round").status_code == 200  # the owner


def test_a_removed_annotator_gets_401_and_their_judgements_stay_theirs(client):
    sid = open_session(client)
    ada = add(client, sid, "Ada")
    made = client.post(f"/api/sessions/{sid}/judgements", json=body(["b1"], ["b2"]), **bearer(ada))
    assert client.delete(f"/api/sessions/{sid}/annotators/{ada['id']}").status_code == 204
    assert client.delete(f"/api/sessions/{sid}/annotators/{ada['id']}").status_code == 404
    assert client.delete(f"/api/sessions/{sid}/annotators/owner").status_code == 422
    response = client.get(f"/api/sessions/{sid}", **bearer(ada))
    assert response.status_code == 401
    assert "removed from their session" in response.json()["detail"]
    assert response.headers["www-authenticate"] == "Bearer"
    history = client.get(f"/api/sessions/{sid}/judgements").json()
    assert history[0]["id"] == made.json()["id"]
    assert history[0]["annotator"] == {"id": ada["id"], "name": "Ada"}
    assert [a["id"] for a in client.get(f"/api/sessions/{sid}/annotators").json()] == ["owner"]
    assert client.get(f"/api/sessions/{sid}", params={"token": "made-up"}).status_code == 401


def test_with_a_server_token_the_owner_needs_it_and_annotators_need_theirs(tmp_path, database_url):
    with make_client(tmp_path, database_url=database_url, token="server-secret") as client:
        owner = {"headers": {"Authorization": "Bearer server-secret"}}
        sid = open_session(client)
        assert client.get(f"/api/sessions/{sid}").status_code == 401
        ada = add(client, sid, "Ada", **owner)
        assert client.get(f"/api/sessions/{sid}", **bearer(ada)).json()["me"]["id"] == ada["id"]
        assert client.get(f"/api/sessions/{sid}", **owner).json()["me"]["owner"] is True
        assert client.post(f"/api/sessions/{sid}/end-round", **bearer(ada)).status_code == 403


ROUNDS_OF = 12
"""Comparisons each of two annotators sends in the interleaving test."""


def _plan(who: int) -> list[dict]:
    """Annotator `who`'s comparisons: groups of 1–3 behaviours, the same for both people."""
    plans = []
    for k in range(ROUNDS_OF):
        m, n = 1 + k % 3, 1 + (k + who) % 2
        picked = [f"b{(k + j) % N}" for j in range(m + n)]
        label = ("left", "right", "equal")[(k + who) % 3]
        plans.append(body(picked[:m], picked[m:], label, client_id=f"{who}-{k}"))
    return plans


def test_two_annotators_interleave_judgements_and_undos_without_losing_any(client):
    sid = open_session(client)
    people = [add(client, sid, "Ada"), add(client, sid, "Bob")]
    start = threading.Barrier(2)
    turns = [threading.Event() for _ in range(ROUNDS_OF * 2 + 1)]
    turns[0].set()
    made: list[list[dict]] = [[], []]
    undone: list[set[int]] = [set(), set()]
    refusals: list[str] = []
    errors: list[BaseException] = []

    def run(who: int) -> None:
        me = bearer(people[who])
        try:
            start.wait()
            for k, plan in enumerate(_plan(who)):
                turns[2 * k + who].wait()  # Ada, Bob, Ada, …: interleaved on purpose
                first = client.post(f"/api/sessions/{sid}/judgements", json=plan, **me)
                again = client.post(f"/api/sessions/{sid}/judgements", json=plan, **me)
                assert (first.status_code, again.status_code) == (201, 200), first.text
                assert again.json()["id"] == first.json()["id"]
                made[who].append(first.json())
                if k % 3 == 0:
                    gone = client.delete(
                        f"/api/sessions/{sid}/judgements/{first.json()['id']}", **me
                    )
                    assert gone.status_code == 200 and gone.json()["undone"]
                    undone[who].add(first.json()["id"])
                theirs = made[1 - who][-1] if made[1 - who] else None
                if theirs is not None:
                    refused = client.delete(f"/api/sessions/{sid}/judgements/{theirs['id']}", **me)
                    assert refused.status_code == 403
                    refusals.append(refused.json()["detail"])
                turns[2 * k + who + 1].set()
        except BaseException as error:
            errors.append(error)
            for turn in turns:
                turn.set()

    threads = [threading.Thread(target=run, args=(who,)) for who in (0, 1)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors, errors

    stored = client.get(f"/api/sessions/{sid}/judgements?include_undone=true").json()
    assert len(stored) == 2 * ROUNDS_OF  # none lost, none doubled
    by_id = {j["id"]: j for j in stored}
    for who, person in enumerate(people):
        for sent in made[who]:
            j = by_id[sent["id"]]
            assert j["annotator"] == {"id": person["id"], "name": person["name"]}
            assert j["undone"] == (j["id"] in undone[who])
            expected = 0 if j["undone"] else max(len(j["left"]), len(j["right"]))
            assert len(j["pairs"]) == expected
    names = {p["id"]: p["name"] for p in people}
    for detail in refusals:
        assert detail.endswith("; only they can undo it")
        assert any(f"was made by {name};" in detail for name in names.values())
    state = client.get(f"/api/sessions/{sid}").json()
    team = {a["id"]: a for a in state["annotators"]}
    for who, person in enumerate(people):
        live = [j for j in made[who] if j["id"] not in undone[who]]
        assert team[person["id"]]["comparisons"] == len(live)
        assert team[person["id"]]["pairs"] == sum(len(j["pairs"]) for j in live)
    assert state["counts"]["comparisons_round"] == sum(team[p["id"]]["comparisons"] for p in people)
    # they judged the same behaviours: their agreement rests on the pairs both labelled
    assert team[people[0]["id"]]["agreement"]["n"] > 0
    lines = [
        json.loads(line) for line in client.get(f"/api/sessions/{sid}/export").text.splitlines()
    ]
    exported = {line["id"]: line for line in lines if line["type"] == "annotator"}
    assert exported[people[1]["id"]]["agreement"] == team[people[1]["id"]]["agreement"]
    judged = [line for line in lines if line["type"] == "judgement"]
    assert {(line["annotator"], line["annotator_id"]) for line in judged} == {
        (p["name"], p["id"]) for p in people
    }
    # the undo of a closed round is still refused as before
    client.post(f"/api/sessions/{sid}/end-round")
    last = made[0][-1]["id"]
    assert (
        client.delete(f"/api/sessions/{sid}/judgements/{last}", **bearer(people[0])).status_code
        == 409
    )


def _events(client, sid, caller, count):
    async def read():
        context = context_of(client)
        viewer = Viewer(caller, None)
        events = []
        async for chunk in session_events(context.db, sid, 0.01, 60.0, 0, viewer):
            text = chunk.decode()
            if text.startswith("event:"):
                head, data = text.strip().split("\ndata: ")
                events.append((head.split("\n")[0].removeprefix("event: "), json.loads(data)))
            if len(events) == count:
                return events
        return events

    return anyio.run(read)


def test_leases_give_two_annotators_different_suggestions_and_the_stream_says_who_answered(
    client,
):
    sid = open_session(client, overlap_share=0.0)
    ada, bob = add(client, sid, "Ada"), add(client, sid, "Bob")
    url = f"/api/sessions/{sid}/rounds/0/next-suggestion"
    to_ada = client.post(url, json={}, **bearer(ada)).json()["suggestion"]
    to_bob = client.post(url, json={}, **bearer(bob)).json()["suggestion"]
    assert to_ada["id"] != to_bob["id"]
    assert (to_ada["left"], to_bob["left"]) == (["b0", "b1"], ["b4"])
    assert client.post(url, json={}, **bearer(ada)).json()["suggestion"] == to_ada  # still hers
    answer = body(to_ada["left"], to_ada["right"], source="suggested")
    made = client.post(f"/api/sessions/{sid}/judgements", json=answer, **bearer(ada)).json()
    assert made["suggestion_id"] == to_ada["id"]

    events = _events(client, sid, Caller(bob["id"], "Bob", sid), 2)
    (kind_state, state), (kind, judged) = events
    assert (kind_state, state["me"]["id"]) == ("state", bob["id"])
    assert kind == "judgement"
    assert judged["annotator"] == {"id": ada["id"], "name": "Ada"}
    assert judged["suggestion_id"] == to_ada["id"]
    # answered: offered to nobody again; Bob keeps his; Ada gets the next free one
    assert client.post(url, json={}, **bearer(bob)).json()["suggestion"]["id"] == to_bob["id"]
    assert client.post(url, json={}, **bearer(ada)).json()["suggestion"]["left"] == ["b7"]


def test_a_shared_pairwise_round_asks_two_annotators_different_pairs(client):
    sid = open_session(client, "pairwise")
    ada, bob = add(client, sid, "Ada"), add(client, sid, "Bob")
    first = client.get(f"/api/sessions/{sid}/pairwise/next", **bearer(ada)).json()
    second = client.get(f"/api/sessions/{sid}/pairwise/next", **bearer(bob)).json()
    assert (first["pair"]["left"], first["pair"]["right"]) == ("b0", "b1")
    assert (second["pair"]["left"], second["pair"]["right"]) == ("b2", "b3")
    # alone (no annotators), the owner gets the queue as before, and nothing is leased
    alone = open_session(client, "pairwise")
    for _ in range(2):
        pair = client.get(f"/api/sessions/{alone}/pairwise/next").json()["pair"]
        assert (pair["left"], pair["right"]) == ("b0", "b1")
