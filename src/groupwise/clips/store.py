"""The clip store: a directory of clips and posters, each under an id that names its bytes.

An id is a SHA-256 in lower-case hex followed by its kind's suffix, e.g.
``"9f86d0…0a08.mp4"``; `ID_PATTERN` is the only form `ClipStore.path` accepts. It is the hash
either of the file's bytes (a clip rendered with its pool: equal bytes get one id, stored
once) or of a *recipe*, everything that renders the file (a clip rendered on demand,
`clips.recipe`: the store keeps the recipe under ``.recipes/`` until, or after, the file is
made). Rendering is deterministic, so either way an id names its content forever and can be
cached by a browser without revalidation. Only ids can address a file: a traversal
(``"../x"``), an absolute path, or anything else that does not match the pattern is
rejected before the file system is touched (the prototype served any path as a "video",
SPEC §10).

Files are written to a temporary file inside the store and renamed into place, so a reader
never sees half a clip, and several processes (the render workers) can write at once.
"""

import hashlib
import os
import re
import tempfile
from pathlib import Path

MEDIA_TYPES: dict[str, str] = {"mp4": "video/mp4", "jpg": "image/jpeg", "png": "image/png"}
"""Suffix → media type of every kind of file the store holds."""

ID_PATTERN = re.compile(r"[0-9a-f]{64}\.(?:mp4|jpg|png)")
"""A clip or poster id: 64 lower-case hex digits, a dot, a suffix of `MEDIA_TYPES`."""

_TMP = ".tmp"
_RECIPES = ".recipes"
_CHUNK = 1 << 20
_KEY = re.compile(r"[0-9a-f]{64}")


class InvalidClipIdError(ValueError):
    """The text is not a well-formed id (`ID_PATTERN`); nothing was looked up."""


class ClipNotFoundError(KeyError):
    """The id is well-formed but no such file is in the store."""


def content_id(data: bytes, suffix: str) -> str:
    """The id of `data` stored as a `suffix` file (a key of `MEDIA_TYPES`)."""
    _check_suffix(suffix)
    return f"{hashlib.sha256(data).hexdigest()}.{suffix}"


def is_valid_id(text: object) -> bool:
    """Whether `text` is a string matching `ID_PATTERN` in full."""
    return isinstance(text, str) and ID_PATTERN.fullmatch(text) is not None


def _check_suffix(suffix: str) -> None:
    if suffix not in MEDIA_TYPES:
        raise ValueError(f"unknown file kind {suffix!r}; choose from {sorted(MEDIA_TYPES)}")


class ClipStore:
    """A directory of content-addressed clips and posters (see the module docstring).

    Picklable (it is only its root path), so worker processes can write into the same store.
    """

    def __init__(self, root: Path | str) -> None:
        self.root = Path(root).resolve()
        self.root.mkdir(parents=True, exist_ok=True)
        (self.root / _TMP).mkdir(exist_ok=True)
        (self.root / _RECIPES).mkdir(exist_ok=True)

    def __repr__(self) -> str:
        return f"ClipStore({str(self.root)!r})"

    def __contains__(self, clip_id: object) -> bool:
        if not is_valid_id(clip_id):
            return False
        path = self._file(str(clip_id))
        return path.is_file() and not path.is_symlink()

    def path(self, clip_id: str) -> Path:
        """The file of an id that is in the store.

        Raises:
            InvalidClipIdError: `clip_id` does not match `ID_PATTERN` (traversal, absolute
                paths, other names); checked before any file system access.
            ClipNotFoundError: well-formed, but not in this store.
        """
        if not is_valid_id(clip_id):
            raise InvalidClipIdError(f"not a clip id: {clip_id!r}")
        path = self._file(clip_id)
        # is_file() follows links: a link planted under an id name must not lead outside
        if path.is_symlink() or not path.is_file():
            raise ClipNotFoundError(clip_id)
        return path

    def media_type(self, clip_id: str) -> str:
        """The media type of an id's file ("video/mp4", "image/jpeg" or "image/png").

        Raises:
            InvalidClipIdError: not a well-formed id.
        """
        if not is_valid_id(clip_id):
            raise InvalidClipIdError(f"not a clip id: {clip_id!r}")
        return MEDIA_TYPES[clip_id.rsplit(".", 1)[1]]

    def put_bytes(self, data: bytes, suffix: str) -> str:
        """Store `data` as a `suffix` file and return its id (a no-op if already stored)."""
        clip_id = content_id(data, suffix)
        if clip_id in self:
            return clip_id
        tmp = self.temporary_file(suffix)
        tmp.write_bytes(data)
        self._place(tmp, clip_id)
        return clip_id

    def put_file(self, tmp: Path, suffix: str) -> str:
        """Move a finished file (made by `temporary_file`) into the store; return its id.

        The file is hashed, then renamed to its id; if that id is already stored, `tmp` is
        deleted instead. `tmp` must be on the store's file system (use `temporary_file`).
        """
        _check_suffix(suffix)
        digest = hashlib.sha256()
        with open(tmp, "rb") as handle:
            while chunk := handle.read(_CHUNK):
                digest.update(chunk)
        clip_id = f"{digest.hexdigest()}.{suffix}"
        if clip_id in self:
            tmp.unlink()
        else:
            self._place(tmp, clip_id)
        return clip_id

    def put_as(self, data: bytes, clip_id: str) -> None:
        """Store `data` under `clip_id` (the hash of its recipe, not of `data`: a file
        rendered on demand), written to a temporary file and renamed into place, so a reader
        never sees part of it; a no-op if already stored.

        Raises:
            InvalidClipIdError: not a well-formed id.
        """
        if not is_valid_id(clip_id):
            raise InvalidClipIdError(f"not a clip id: {clip_id!r}")
        if clip_id in self:
            return
        tmp = self.temporary_file(clip_id.rsplit(".", 1)[1])
        try:
            tmp.write_bytes(data)
            self._place(tmp, clip_id)
        finally:
            tmp.unlink(missing_ok=True)

    def put_recipe(self, key: str, data: bytes) -> None:
        """Keep the recipe `data` (`clips.recipe`) of the files with ids ``key.<suffix>``.

        Raises:
            InvalidClipIdError: `key` is not 64 lower-case hex digits.
        """
        path = self._recipe(key)
        if path.is_file():
            return
        tmp = self.temporary_file("npz")
        try:
            tmp.write_bytes(data)
            os.chmod(tmp, 0o644)
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)

    def recipe(self, clip_id: str) -> Path | None:
        """The recipe file of an id rendered on demand, None when the store has none (an id
        of a file stored with its pool, or unknown).

        Raises:
            InvalidClipIdError: not a well-formed id.
        """
        if not is_valid_id(clip_id):
            raise InvalidClipIdError(f"not a clip id: {clip_id!r}")
        path = self._recipe(clip_id.rsplit(".", 1)[0])
        return path if path.is_file() and not path.is_symlink() else None

    def temporary_file(self, suffix: str) -> Path:
        """A fresh, empty file inside the store's temporary folder, named ``*.suffix``."""
        if suffix != "npz":
            _check_suffix(suffix)
        fd, name = tempfile.mkstemp(suffix=f".{suffix}", dir=self.root / _TMP)
        os.close(fd)
        return Path(name)

    def ids(self) -> list[str]:
        """Every id in the store, sorted."""
        return sorted(p.name for p in self.root.iterdir() if is_valid_id(p.name) and p.is_file())

    def _file(self, clip_id: str) -> Path:
        return self.root / clip_id

    def _recipe(self, key: str) -> Path:
        if _KEY.fullmatch(key) is None:
            raise InvalidClipIdError(f"not a recipe key: {key!r}")
        return self.root / _RECIPES / f"{key}.npz"

    def _place(self, tmp: Path, clip_id: str) -> None:
        os.chmod(tmp, 0o644)
        # atomic on one file system; a concurrent writer of the same id writes equal bytes
        os.replace(tmp, self._file(clip_id))
