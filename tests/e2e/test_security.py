"""State changes in a real browser (docs/app.md, "Security"): the app's own page may post
only JSON, and a page on another site can change nothing, whatever it sends.

The foreign site is a tiny `http.server` on another port under the name ``localhost`` (the
app is at ``127.0.0.1``), serving a page that posts a judgement as a plain HTML form (the
classic cross-site request forgery of a JSON API: ``enctype="text/plain"`` makes the body
valid JSON), as a ``no-cors`` fetch, and posts a bodiless form to end the round.
"""

import http.server
import json
import socket
import threading
from collections.abc import Iterator
from functools import partial
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("playwright.sync_api")
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server


def _judgement(client_id: str) -> dict[str, Any]:
    return {
        "client_id": client_id,
        "round": 0,
        "left": ["b1"],
        "right": ["b2"],
        "label": "left",
        "source": "explored",
    }


def _stored(server: Server, sid: str, client_id: str) -> int:
    rows = server.db_rows(
        "SELECT count(*) FROM judgements WHERE session_id = ? AND client_id = ?", sid, client_id
    )
    return int(rows[0][0])


@pytest.fixture(scope="module")
def session(server: Server) -> str:
    return str(server.new_session("groupwise"))


@pytest.fixture
def foreign_site(tmp_path: Path) -> Iterator[tuple[str, Path]]:
    """(base URL, directory) of another site: http://localhost:<another port>."""
    handler = partial(http.server.SimpleHTTPRequestHandler, directory=str(tmp_path))
    handler.log_message = lambda *args: None  # type: ignore[method-assign]  # quiet test output
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://localhost:{port}", tmp_path
    httpd.shutdown()
    httpd.server_close()


def test_the_own_page_may_post_json_but_not_text(server: Server, session: str, page: Page):
    page.goto(f"{server.url}/api/health")  # any page of the app's own origin
    post = """async ([url, body, type]) => {
        const response = await fetch(url, {
            method: "POST", headers: {"Content-Type": type}, body: JSON.stringify(body)});
        return [response.status, (await response.json()).detail ?? null];
    }"""
    url = f"/api/sessions/{session}/judgements"
    text = page.evaluate(post, [url, _judgement("page-text"), "text/plain"])
    assert text == [415, "send the body as application/json, not text/plain"]
    assert _stored(server, session, "page-text") == 0
    as_json = page.evaluate(post, [url, _judgement("page-json"), "application/json"])
    assert as_json == [201, None]  # Chromium's Origin and Sec-Fetch-Site: same-origin pass
    assert _stored(server, session, "page-json") == 1


def test_a_page_on_another_site_changes_nothing(
    server: Server, session: str, page: Page, foreign_site: tuple[str, Path]
):
    base, directory = foreign_site
    target = f"{server.url}/api/sessions/{session}"
    # a text/plain form body "<name>=<value>": the name opens the JSON, the value closes it
    form_body = json.dumps(_judgement("foreign-form"))[:-1] + ', "pad": "'
    (directory / "attack.html").write_text(
        f"""<!doctype html><title>elsewhere</title>
<form id="judge" method="POST" action="{target}/judgements" enctype="text/plain">
  <input type="hidden" name='{form_body}' value='"}}'></form>
<form id="end" method="POST" action="{target}/end-round"></form>
<script>
  window.fetched = fetch("{target}/judgements", {{
      method: "POST", mode: "no-cors", headers: {{"Content-Type": "text/plain"}},
      body: JSON.stringify({json.dumps(_judgement("foreign-fetch"))})}})
    .then(() => "sent", (error) => String(error));
</script>"""
    )
    statuses: dict[str, list[int]] = {}
    page.on(
        "response",
        lambda r: (
            statuses.setdefault(r.url, []).append(r.status) if r.url.startswith(target) else 0
        ),
    )
    page.goto(f"{base}/attack.html")
    assert page.evaluate("window.fetched") == "sent"  # opaque: the page learns nothing
    with page.expect_navigation() as judged:
        page.evaluate("document.getElementById('judge').submit()")
    assert judged.value.status == 403
    assert "may not change anything here" in judged.value.json()["detail"]
    page.goto(f"{base}/attack.html")
    with page.expect_navigation() as ended:
        page.evaluate("document.getElementById('end').submit()")
    assert ended.value.status == 403

    assert statuses[f"{target}/judgements"] and set(statuses[f"{target}/judgements"]) == {403}
    for client_id in ("foreign-form", "foreign-fetch"):
        assert _stored(server, session, client_id) == 0, client_id
    assert server.api("GET", f"/api/sessions/{session}")["phase"] == "ready"
