"""Host names, tokens, body limits, CORS and the static front end, in-process."""

import pytest
from tests.unit.server.conftest import make_client

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
