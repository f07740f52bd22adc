"""The clip store: content-derived ids, and nothing outside the store addressable by id."""

import hashlib
from pathlib import Path
from typing import Any

import pytest

from groupwise.clips.store import (
    ClipNotFoundError,
    ClipStore,
    InvalidClipIdError,
    content_id,
    is_valid_id,
)


def test_an_id_is_the_sha256_of_the_bytes_plus_the_suffix(tmp_path: Path) -> None:
    store = ClipStore(tmp_path / "clips")
    clip_id = store.put_bytes(b"frames", "mp4")
    assert clip_id == hashlib.sha256(b"frames").hexdigest() + ".mp4"
    assert store.path(clip_id).read_bytes() == b"frames"
    assert store.media_type(clip_id) == "video/mp4"
    assert clip_id in store and store.ids() == [clip_id]


def test_equal_bytes_are_stored_once(tmp_path: Path) -> None:
    store = ClipStore(tmp_path)
    assert store.put_bytes(b"x", "jpg") == store.put_bytes(b"x", "jpg") == content_id(b"x", "jpg")
    tmp = store.temporary_file("jpg")
    tmp.write_bytes(b"x")
    assert store.put_file(tmp, "jpg") == content_id(b"x", "jpg")
    assert not tmp.exists()
    assert len(store.ids()) == 1


@pytest.mark.parametrize(
    "bad",
    [
        "../secret.mp4",
        "../" + "a" * 64 + ".mp4",
        "/etc/passwd",
        "a" * 64 + ".mp4/../../x",
        "A" * 64 + ".mp4",  # upper case
        "a" * 63 + ".mp4",
        "a" * 64 + ".exe",
        "a" * 64 + ".mp4\n",
        "a" * 64,
        "",
        ".tmp",
    ],
)
def test_malformed_ids_are_rejected_before_touching_the_file_system(
    tmp_path: Path, bad: str
) -> None:
    store = ClipStore(tmp_path / "store")
    (tmp_path / "secret.mp4").write_bytes(b"outside")
    assert not is_valid_id(bad)
    assert bad not in store
    with pytest.raises(InvalidClipIdError):
        store.path(bad)


def test_a_well_formed_unknown_id_is_not_found(tmp_path: Path) -> None:
    store = ClipStore(tmp_path)
    with pytest.raises(ClipNotFoundError):
        store.path("0" * 64 + ".mp4")


def test_a_symlink_or_folder_with_an_id_name_is_not_served(tmp_path: Path) -> None:
    store = ClipStore(tmp_path / "store")
    name = "b" * 64 + ".png"
    (store.root / name).mkdir()
    with pytest.raises(ClipNotFoundError):
        store.path(name)


def test_a_link_under_an_id_name_does_not_lead_outside(tmp_path: Path) -> None:
    store = ClipStore(tmp_path / "store")
    outside = tmp_path / "secret.mp4"
    outside.write_bytes(b"outside")
    name = content_id(b"outside", "mp4")
    (store.root / name).symlink_to(outside)
    assert name not in store
    with pytest.raises(ClipNotFoundError):
        store.path(name)


def test_non_string_ids_are_rejected(tmp_path: Path) -> None:
    store = ClipStore(tmp_path)
    not_text: Any = None
    with pytest.raises(InvalidClipIdError):
        store.path(not_text)
