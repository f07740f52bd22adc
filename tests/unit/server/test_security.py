"""Host names, same-origin state changes, tokens, body limits and types, CORS and the
static front end, in-process."""

import json

import pytest
from tests.unit.server.conftest import make_client

from groupwise.server.app import own_body_types
from groupwise.server.config import LOOPBACK_HOSTS
from groupwise.server.security import trusted_hosts

TOKEN = "s3cret-token"


@pytest.fixture
def guarded(tmp_path):
    with make_client(tmp_path, token=TOKEN) as client:
        yield client


def test_a_token_is_needed_for_api_and_clips(guarded):
    for path in ("/api/sessions", "/api/health", "/api/openapi.json", "/clips/x.mp4"):
        response = guarded.get(path)
        assert response.status_code == 401, path
        assert "token" in response.json()["detail"]
        assert response.headers["www-authenticate"] == "Bearer"
    assert (
        guarded.get("/api/sessions", headers={"Authorization": "Bearer wrong"}).status_code == 401
    )
    assert guarded.get("/api/sessions", params={"token": "wrong"}).status_code == 401
    ok = guarded.get("/api/sessions", headers={"Authorization": f"Bearer {TOKEN}"})
    assert ok.status_code == 200
    assert guarded.get("/api/sessions", params={"token": TOKEN}).status_code == 200
    # the page itself is public: it holds no data and asks for the token in its URL
    assert guarded.get("/").status_code == 200


def test_foreign_host_names_are_refused(tmp_path):
    with make_client(tmp_path, allowed_hosts=LOOPBACK_HOSTS) as client:
        assert client.get("http://127.0.0.1:8000/api/envs").status_code == 200
        assert client.get("http://localhost:8000/api/envs").status_code == 200
        rebound = client.get("http://attacker.example:8000/api/envs")
        # Starlette's TrustedHostMiddleware answers in plain text, not JSON
        assert rebound.status_code == 400 and rebound.text == "Invalid host header"


@pytest.mark.parametrize(
    ("header", "status"),
    [
        ("127.0.0.1:8000", 200),
        ("[::1]:8000", 200),
        ("LocalHost", 200),
        ("localhost.attacker.example", 400),
        ("[::2]:8000", 400),
        ("", 400),
    ],
)
def test_host_headers(tmp_path, header, status):
    with make_client(tmp_path, allowed_hosts=LOOPBACK_HOSTS) as client:
        assert client.get("/api/envs", headers={"host": header}).status_code == status


def test_trusted_host_patterns():
    assert trusted_hosts(LOOPBACK_HOSTS) == ["127.0.0.1", "localhost", "[::1]"]
    assert trusted_hosts(None) == ["*"]


def test_a_token_is_checked_after_the_host(tmp_path):
    with make_client(tmp_path, token=TOKEN, allowed_hosts=LOOPBACK_HOSTS) as client:
        assert client.get("http://attacker.example/api/envs").status_code == 400
        assert client.get("http://localhost/api/envs").status_code == 401


def test_bodies_over_one_mebibyte_are_413(client):
    big = b"{" + b" " * (1 << 20) + b"}"
    announced = client.post(
        "/api/sessions", content=big, headers={"content-type": "application/json"}
    )
    assert announced.status_code == 413 and "larger than" in announced.json()["detail"]

    def chunks():
        for _ in range(20):
            yield b" " * 60_000

    streamed = client.post(
        "/api/sessions/import", content=chunks(), headers={"content-type": "application/x-ndjson"}
    )
    assert streamed.status_code == 413


def test_no_cors_headers(client):
    response = client.get("/api/envs", headers={"Origin": "https://elsewhere.example"})
    assert not [h for h in response.headers if h.lower().startswith("access-control")]
    preflight = client.options(
        "/api/sessions",
        headers={"Origin": "https://elsewhere.example", "Access-Control-Request-Method": "POST"},
    )
    assert not [h for h in preflight.headers if h.lower().startswith("access-control")]


def test_without_a_built_web_ui_the_root_says_how_to_build_it(client):
    response = client.get("/")
    assert response.status_code == 200 and "npm run build" in response.text


def test_a_built_web_ui_is_served_at_the_root(tmp_path):
    dist = tmp_path / "dist"
    (dist / "assets").mkdir(parents=True)
    (dist / "index.html").write_text("<!doctype html><title>the page</title>")
    (dist / "assets" / "app.js").write_text("console.log(1)")
    with make_client(tmp_path, static_dir=dist) as client:
        assert "the page" in client.get("/").text
        assert client.get("/assets/app.js").text == "console.log(1)"
        assert client.get("/api/envs").status_code == 200
        assert client.get("/api/unknown").status_code == 404


# -- state changes: same origin and JSON bodies only (docs/app.md, "Security") ----------------


def _judgement(round_index: int = 0, left: str = "b1", right: str = "b2") -> dict:
    return {
        "client_id": f"guard-{left}-{right}",
        "round": round_index,
        "left": [left],
        "right": [right],
        "label": "left",
        "source": "explored",
    }


def _stored(client, sid: str) -> set[str]:
    return {j["client_id"] for j in client.get(f"/api/sessions/{sid}/judgements").json()}


@pytest.mark.parametrize(
    "content_type", ["text/plain", "application/x-www-form-urlencoded", "multipart/form-data"]
)
def test_a_judgement_that_is_not_json_is_415_and_stores_nothing(prepared, content_type):
    client, sid, _ = prepared
    body = _judgement(left="b3", right="b4")
    response = client.post(
        f"/api/sessions/{sid}/judgements",
        content=json.dumps(body),
        headers={"content-type": content_type},
    )
    assert response.status_code == 415
    assert response.json() == {"detail": f"send the body as application/json, not {content_type}"}
    assert body["client_id"] not in _stored(client, sid)


def test_a_body_without_content_type_is_415_announced_or_streamed(prepared):
    client, sid, _ = prepared
    body = json.dumps(_judgement(left="b5", right="b6")).encode()
    announced = client.post(f"/api/sessions/{sid}/judgements", content=body)
    assert announced.status_code == 415 and "names no Content-Type" in announced.json()["detail"]
    streamed = client.post(f"/api/sessions/{sid}/judgements", content=iter([body]))
    assert streamed.status_code == 415 and "names no Content-Type" in streamed.json()["detail"]
    assert "guard-b5-b6" not in _stored(client, sid)


def test_json_with_a_charset_and_bodiless_state_changes_pass(client):
    created = client.post(
        "/api/sessions",
        content=json.dumps({"env": "GridWorld"}),
        headers={"content-type": "application/json; charset=utf-8"},
    )
    assert created.status_code == 201, created.text
    # no body, no Content-Type (curl -X POST, the page's fetch without a body): not a 415
    assert client.post(f"/api/sessions/{created.json()['id']}/pause").status_code == 409


@pytest.mark.parametrize(
    "headers",
    [
        {"Origin": "https://attacker.example"},
        {"Origin": "null"},
        {"Origin": "http://testserver:8080"},  # another port is another origin
        {"Sec-Fetch-Site": "cross-site"},
        {"Sec-Fetch-Site": "same-site"},  # e.g. another port on 127.0.0.1
        {"Sec-Fetch-Site": "same-origin", "Origin": "https://attacker.example"},
    ],
)
def test_state_changes_from_other_sites_are_403_and_store_nothing(prepared, headers):
    client, sid, _ = prepared
    body = _judgement(left="b7", right="b8")
    response = client.post(f"/api/sessions/{sid}/judgements", json=body, headers=headers)
    assert response.status_code == 403
    assert "may not change anything here" in response.json()["detail"]
    assert body["client_id"] not in _stored(client, sid)
    assert client.post(f"/api/sessions/{sid}/end-round", headers=headers).status_code == 403
    assert client.get(f"/api/sessions/{sid}").json()["phase"] == "ready"


@pytest.mark.parametrize(
    "headers",
    [
        {"Origin": "http://testserver", "Sec-Fetch-Site": "same-origin"},  # the app's own page
        {"Origin": "HTTP://TestServer"},
        {"Sec-Fetch-Site": "none"},  # the user's own navigation
        {},  # no browser: a script or the CLI
    ],
)
def test_state_changes_from_the_own_page_or_no_browser_pass(prepared, headers):
    client, sid, _ = prepared
    body = _judgement(left="b9", right="b10")
    body["client_id"] += str(sorted(headers.items()))
    response = client.post(f"/api/sessions/{sid}/judgements", json=body, headers=headers)
    assert response.status_code == 201, response.text
    assert client.delete(
        f"/api/sessions/{sid}/judgements/{response.json()['id']}", headers=headers
    ).is_success


def test_reads_from_other_sites_are_answered(client):
    # without CORS headers the foreign page cannot read them; a <video src> may show a clip
    headers = {"Origin": "https://attacker.example", "Sec-Fetch-Site": "cross-site"}
    assert client.get("/api/envs", headers=headers).status_code == 200


def test_a_script_with_the_token_and_no_browser_headers_may_change_things(guarded):
    auth = {"Authorization": f"Bearer {TOKEN}"}
    created = guarded.post("/api/sessions", json={"env": "GridWorld"}, headers=auth)
    assert created.status_code == 201
    cross = guarded.post(
        "/api/sessions", json={"env": "GridWorld"}, headers={**auth, "Sec-Fetch-Site": "cross-site"}
    )
    assert cross.status_code == 403  # a token in a foreign page's URL does not help it
    assert guarded.post("/api/sessions", content=b"env=x", headers=auth).status_code == 415


def test_the_import_keeps_its_own_types_and_the_origin_check(client):
    assert own_body_types(client.app) == frozenset({"/api/sessions/import"})
    text = client.post(
        "/api/sessions/import", content=b"a=b", headers={"content-type": "text/plain"}
    )
    assert text.status_code == 415 and "application/x-ndjson" in text.json()["detail"]
    empty = client.post(
        "/api/sessions/import", content=b"", headers={"content-type": "application/x-ndjson"}
    )
    assert empty.status_code == 422  # reached the route: its own type check passed
    cross = client.post(
        "/api/sessions/import",
        content=b"",
        headers={"content-type": "application/x-ndjson", "Origin": "https://attacker.example"},
    )
    assert cross.status_code == 403


@pytest.mark.parametrize(
    ("body", "detail"),
    [
        (b"", "body: Field required"),
        (b"nul", "request body is not valid JSON: Expecting value at line 1 column 1"),
        (
            b'{"env": "GridWorld",\n}',
            "request body is not valid JSON: Expecting property name enclosed in double quotes "
            "at line 2 column 1",
        ),
        (b"[1, 2", "request body is not valid JSON: Expecting ',' delimiter at line 1 column 6"),
    ],
)
def test_malformed_json_names_where_it_breaks(client, body, detail):
    response = client.post(
        "/api/sessions", content=body, headers={"content-type": "application/json"}
    )
    assert response.status_code in (400, 422)
    assert response.json() == {"detail": detail}


@pytest.mark.parametrize(
    ("body", "offset"),
    [
        (b'{"env": "Grid\xffWorld"}', 13),  # a byte UTF-8 never uses
        (b'{"env": "\xc3("}', 9),  # a lead byte without its continuation
    ],
)
def test_a_body_that_is_not_utf8_is_a_clear_400(client, body, offset):
    response = client.post(
        "/api/sessions", content=body, headers={"content-type": "application/json"}
    )
    assert response.status_code == 400
    detail = response.json()["detail"]
    assert detail.startswith("request body is not valid UTF-8 JSON: invalid byte 0x")
    assert detail.endswith(f"at offset {offset}")


def test_other_http_errors_keep_their_answer(client):
    response = client.get("/clips/not-a-clip")
    assert response.status_code == 404
    assert response.json() == {"detail": "there is no such clip"}


def test_the_schema_documents_the_guards_answers_on_state_changes(client):
    paths = client.get("/api/openapi.json").json()["paths"]
    judgements = paths["/api/sessions/{session_id}/judgements"]
    assert {"403", "415"} <= set(judgements["post"]["responses"])
    # a read takes any body type; its 403 is an annotator's token for another session
    assert "415" not in judgements["get"]["responses"]
