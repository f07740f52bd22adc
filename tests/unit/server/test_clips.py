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
