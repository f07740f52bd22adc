"""Clips rendered on demand (issue 22): once per id however many ask, the newest first, a
failure leaves nothing in the store, and the bytes are the eagerly rendered clip's."""

import asyncio
import threading
from concurrent.futures import Future
from pathlib import Path

import numpy as np
import pytest

from groupwise.clips import on_demand
from groupwise.clips.on_demand import (
    OnDemandClips,
    RenderBusyError,
    RenderFailedError,
    local_renderer,
)
from groupwise.clips.recipe import RenderedMedia
from groupwise.clips.store import ClipNotFoundError, ClipStore, InvalidClipIdError
from groupwise.pool.publish import PublishConfig, prepare_pool
from groupwise.rl.policy_files import load_policy


class HeldBackend:
    """Renders nothing until the test lets each submitted recipe finish."""

    def __init__(self, capacity: int = 1) -> None:
        self.capacity = capacity
        self.submitted: list[tuple[bytes, bool, Future[RenderedMedia]]] = []
        self.warmed = 0

    def submit(self, recipe: bytes, clip: bool) -> "Future[RenderedMedia]":
        future: Future[RenderedMedia] = Future()
        self.submitted.append((recipe, clip, future))
        return future

    def warm(self, recipe: bytes) -> None:
        self.warmed += 1

    def close(self) -> None:
        pass


def _recipe(store: ClipStore, name: str) -> str:
    key = (name * 64)[:64]
    store.put_recipe(key, f"recipe {name}".encode())
    return key


def _finish_soon(future: "Future[RenderedMedia]", media: RenderedMedia | BaseException) -> None:
    def finish() -> None:
        if isinstance(media, BaseException):
            future.set_exception(media)
        else:
            future.set_result(media)

    threading.Timer(0.05, finish).start()


def test_requests_for_one_clip_render_it_once_then_it_is_a_file(tmp_path: Path) -> None:
    store = ClipStore(tmp_path)
    backend = HeldBackend()
    clips = OnDemandClips(store, backend)
    key = _recipe(store, "a")

    async def ask() -> list[Path]:
        pending = [asyncio.ensure_future(clips.file(f"{key}.mp4")) for _ in range(5)]
        await asyncio.sleep(0.01)
        assert len(backend.submitted) == 1
        recipe, clip, future = backend.submitted[0]
        assert (recipe, clip) == (b"recipe a", True)
        _finish_soon(future, RenderedMedia(b"the clip", b"\xff\xd8 the poster"))
        return await asyncio.gather(*pending)

    paths = asyncio.run(ask())
    assert {p.read_bytes() for p in paths} == {b"the clip"}
    assert store.path(f"{key}.jpg").read_bytes() == b"\xff\xd8 the poster"  # with its clip
    assert asyncio.run(clips.file(f"{key}.mp4")).read_bytes() == b"the clip"
    assert len(backend.submitted) == 1 and clips.rendered == 1
    assert backend.warmed == 1  # a stored file of an on-demand id starts the renderers


def test_a_poster_alone_is_rendered_without_its_clip(tmp_path: Path) -> None:
    store = ClipStore(tmp_path)
    backend = HeldBackend()
    clips = OnDemandClips(store, backend)
    key = _recipe(store, "b")

    async def ask() -> Path:
        pending = asyncio.ensure_future(clips.file(f"{key}.jpg"))
        await asyncio.sleep(0.01)
        _, clip, future = backend.submitted[0]
        assert clip is False
        _finish_soon(future, RenderedMedia(None, b"poster"))
        return await pending

    assert asyncio.run(ask()).read_bytes() == b"poster"
    assert f"{key}.mp4" not in store


def test_unknown_and_malformed_ids(tmp_path: Path) -> None:
    clips = OnDemandClips(ClipStore(tmp_path), HeldBackend())
    with pytest.raises(ClipNotFoundError):
        asyncio.run(clips.file("0" * 64 + ".mp4"))
    for bad in ("../x.mp4", "0" * 64, ".recipes"):
        with pytest.raises(InvalidClipIdError):
            asyncio.run(clips.file(bad))


def test_a_failed_render_stores_nothing_and_is_tried_again(tmp_path: Path) -> None:
    store = ClipStore(tmp_path)
    backend = HeldBackend()
    clips = OnDemandClips(store, backend)
    key = _recipe(store, "c")

    async def ask() -> None:
        pending = asyncio.ensure_future(clips.file(f"{key}.mp4"))
        await asyncio.sleep(0.01)
        _finish_soon(backend.submitted[-1][2], RuntimeError("ffmpeg is gone"))
        await pending

    with pytest.raises(RenderFailedError, match=f"{key}.mp4 could not be rendered.*ffmpeg is gone"):
        asyncio.run(ask())
    assert store.ids() == [] and list((store.root / ".tmp").iterdir()) == []
    with pytest.raises(RenderFailedError):
        asyncio.run(ask())
    assert len(backend.submitted) == 2  # not remembered as failed: asked again, tried again


def test_the_newest_request_is_rendered_next_and_the_oldest_dropped(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(on_demand, "MAX_WAITING", 2)
    store = ClipStore(tmp_path)
    backend = HeldBackend(capacity=1)
    clips = OnDemandClips(store, backend)
    keys = [_recipe(store, name) for name in "def0"]

    async def ask() -> list[object]:
        pending = []
        for key in keys:  # d runs; e, f, 0 wait, and e, the oldest, is dropped
            pending.append(asyncio.ensure_future(clips.file(f"{key}.mp4")))
            await asyncio.sleep(0.01)
        for _ in range(3):
            recipe, _, future = backend.submitted[-1]
            _finish_soon(future, RenderedMedia(recipe, b"poster"))
            await asyncio.sleep(0.2)
        return await asyncio.gather(*pending, return_exceptions=True)

    outcomes = asyncio.run(ask())
    assert [recipe for recipe, _, _ in backend.submitted] == [b"recipe d", b"recipe 0", b"recipe f"]
    assert isinstance(outcomes[1], RenderBusyError)
    assert [isinstance(o, Path) for o in outcomes] == [True, False, True, True]


@pytest.fixture(scope="module")
def gridworld_pools(tmp_path_factory: pytest.TempPathFactory) -> tuple[ClipStore, object, object]:
    """The same GridWorld behaviours published eagerly and on demand into one store."""
    root = tmp_path_factory.mktemp("pools")
    store = ClipStore(root / "clips")
    published = []
    for clips in ("eager", "on_demand"):
        cfg = PublishConfig(env="GridWorld", width=32, height=32, workers=0, clips=clips)
        policy = load_policy("random", "GridWorld")
        rng = np.random.default_rng(7)
        out = root / clips
        published.append(
            prepare_pool(cfg, policy, rng, out, size=6, length=30, store=store, show_progress=False)
        )
    return store, published[0], published[1]


def test_on_demand_clips_are_the_eagerly_rendered_bytes(gridworld_pools) -> None:
    store, eager, lazy = gridworld_pools
    assert lazy.timings.frames == 6  # a poster each, no clip yet
    assert all(p in store for p in lazy.posters) and not any(c in store for c in lazy.clips)
    clips = local_renderer(store, workers=1)
    try:

        async def ask() -> list[Path]:
            return await asyncio.gather(*(clips.file(c) for c in lazy.clips))

        paths = asyncio.run(ask())
    finally:
        clips.close()
    for path, clip, poster, eager_poster in zip(
        paths, eager.clips, lazy.posters, eager.posters, strict=True
    ):
        assert path.read_bytes() == store.path(clip).read_bytes()
        assert store.path(poster).read_bytes() == store.path(eager_poster).read_bytes()
    assert clips.rendered == 6
