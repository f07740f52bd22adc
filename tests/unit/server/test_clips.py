"""Clips are served by store id only, with HTTP Range; everything else is 404."""

import pytest
from tests.unit.server.conftest import context_of


@pytest.fixture
def stored(client):
    store = context_of(client).clips
    data = bytes(range(256)) * 40
    return client, store.put_bytes(data, "mp4"), data


def test_a_clip_by_id(stored):
    client, clip_id, data = stored
    response = client.get(f"/clips/{clip_id}")
    assert response.status_code == 200
    assert response.content == data
    assert response.headers["content-type"] == "video/mp4"
    assert "immutable" in response.headers["cache-control"]


def test_range_requests_for_seeking(stored):
    client, clip_id, data = stored
    response = client.get(f"/clips/{clip_id}", headers={"Range": "bytes=100-199"})
    assert response.status_code == 206
    assert response.content == data[100:200]
    assert response.headers["content-range"] == f"bytes 100-199/{len(data)}"


@pytest.mark.parametrize(
    "path",
    [
        "/clips/..%2F..%2Fetc%2Fpasswd",
        "/clips/..%2Fgroupwise.db",
        "/clips/%2e%2e%2fgroupwise.db",
        "/clips/groupwise.db",
        "/clips/" + "0" * 64 + ".mp4",  # well-formed, not stored
        "/clips/" + "A" * 64 + ".mp4",
        "/clips/" + "0" * 64 + ".exe",
        "/clips/.tmp",
        "/clips/",
    ],
)
def test_anything_but_a_stored_id_is_404(stored, path):
    client, _, _ = stored
    assert client.get(path).status_code == 404


def test_a_link_planted_under_an_id_name_is_not_followed(stored, tmp_path):
    client, _, _ = stored
    store = context_of(client).clips
    secret = tmp_path / "secret.txt"
    secret.write_text("private")
    planted = "1" * 64 + ".mp4"
    (store.root / planted).symlink_to(secret)
    assert client.get(f"/clips/{planted}").status_code == 404


class _Backend:
    """Renders every recipe at once into fixed bytes, or fails with `error`."""

    capacity = 1

    def __init__(self, error: Exception | None = None) -> None:
        self.error, self.calls = error, 0

    def submit(self, recipe, clip):
        from concurrent.futures import Future

        from groupwise.clips.recipe import RenderedMedia

        self.calls += 1
        future = Future()
        if self.error is not None:
            future.set_exception(self.error)
        else:
            future.set_result(RenderedMedia(b"clip of " + recipe if clip else None, b"poster"))
        return future

    def warm(self, recipe):
        pass

    def close(self):
        pass


def _on_demand(client, backend):
    from groupwise.clips.on_demand import OnDemandClips

    store = context_of(client).clips
    client.app.state.clip_renderer = OnDemandClips(store, backend)
    key = "7" * 64
    store.put_recipe(key, b"recipe")
    return store, key


def test_a_clip_published_on_demand_is_rendered_on_the_first_request(client):
    backend = _Backend()
    store, key = _on_demand(client, backend)
    for _ in range(2):
        response = client.get(f"/clips/{key}.mp4")
        assert response.status_code == 200
        assert response.content == b"clip of recipe"
        assert "immutable" in response.headers["cache-control"]
    assert backend.calls == 1 and store.path(f"{key}.jpg").read_bytes() == b"poster"


def test_a_clip_that_cannot_be_rendered_is_a_clear_500_and_stores_nothing(client):
    store, key = _on_demand(client, _Backend(RuntimeError("no GL context")))
    response = client.get(f"/clips/{key}.mp4")
    assert response.status_code == 500
    assert response.json()["detail"] == (
        f"{key}.mp4 could not be rendered: RuntimeError: no GL context"
    )
    assert f"{key}.mp4" not in store and store.ids() == []


def test_a_served_app_starts_its_clip_renderer_with_it(tmp_path):
    """The render processes start with the server, not with the first clip a person asks
    for (that one waited 10-11 s for them on a busy machine)."""
    from tests.unit.server.conftest import make_client

    with make_client(tmp_path, start_worker=True) as client:
        backend = client.app.state.clip_renderer.backend  # type: ignore[attr-defined]  # app.state is untyped
        assert backend._executor is not None  # started, not waiting for a first request


def test_a_served_app_whose_clip_renderer_cannot_start_serves_all_the_same(tmp_path, caplog):
    """Starting the render processes with the server saves the first clip's wait; a renderer
    that cannot start then (here: no render process allowed) is logged and the server
    serves. Its failed startup had left `groupwise serve` alive but refusing every
    connection, waiting at exit for its training worker, which trained on."""
    from tests.unit.server.conftest import make_client

    with make_client(tmp_path, start_worker=True, clip_workers=0) as client:
        assert client.get("/api/health").status_code == 200
        assert client.get("/api/sessions").status_code == 200
    assert "the clip render processes did not start" in caplog.text
