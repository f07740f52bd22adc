"""Clips rendered when they are first asked for (issue 22, item 3).

A pool published with ``clips="on_demand"`` (`pool.publish`) has a poster per behaviour and,
for each clip, a recipe in the clip store (`clips.recipe`). `OnDemandClips.file` answers a
store id: a stored file at once; an id with a recipe but no file yet is rendered first, by
a `RenderBackend`, and stored (temporary file, then rename: a failed render leaves nothing
behind), so the second request is a file.

- **Once per id**: concurrent requests for one id wait on the same render.
- **Newest first**: renders wait in a stack, at most `RenderBackend.capacity` run at a time,
  and the most recently asked-for starts next, so the clip a person hovers now is not queued
  behind the ones the pointer swept over; past `MAX_WAITING` waiting renders the oldest are
  dropped (their requests answer "busy": the page asks again when it shows them again).
- **Where**: `ProcessBackend`, spawn processes of the server (default), or `RayBackend`,
  tasks on a Ray cluster (`groupwise serve --ray ADDRESS`); both run `render_recipe_bytes`
  and return the encoded bytes, which this process stores.

The server calls it from its event loop (`await file(...)`); nothing here blocks that loop
longer than a file-system check, and the render processes import MuJoCo, not the server.
"""

import asyncio
import functools
import logging
import multiprocessing
import os
import threading
import time
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Protocol

from groupwise.clips.recipe import ClipRecipe, RenderedMedia
from groupwise.clips.store import ClipNotFoundError, ClipStore

log = logging.getLogger(__name__)

MAX_WAITING = 64
"""Renders waiting for a free render process, at most (the oldest are dropped)."""

RENDER_TIMEOUT_S = 120.0
"""A request waits this long for its render, at most."""


class RenderFailedError(RuntimeError):
    """A clip or poster could not be rendered (the message says which and why)."""


class RenderBusyError(RenderFailedError):
    """The render was dropped from a full queue, or timed out; asking again may succeed."""


def render_recipe_bytes(recipe: bytes, clip: bool) -> RenderedMedia:
    """Render a recipe (`ClipRecipe.to_bytes`): its clip and poster, or its poster alone.
    Runs in a render process or a Ray task, with that process's cached rendering env."""
    from groupwise.clips.recipe import render_recipe
    from groupwise.envs.rendering import ensure_gl_backend

    ensure_gl_backend()
    return render_recipe(ClipRecipe.from_bytes(recipe), clip=clip)


def load_renderer() -> None:
    """Import what rendering needs and choose the GL backend: most of a render process's
    cold start (about 10 s on a busy 2-core machine), done when the server starts."""
    from groupwise.clips.recipe import render_recipe  # noqa: F401
    from groupwise.envs.rendering import ensure_gl_backend

    ensure_gl_backend()


def warm_recipe_env(recipe: bytes) -> None:
    """Make this process's rendering env for a recipe's settings and draw one frame."""
    from groupwise.clips.env_cache import warm_up
    from groupwise.envs.rendering import ensure_gl_backend

    ensure_gl_backend()
    warm_up(ClipRecipe.from_bytes(recipe).settings)


PARENT_POLL_S = 1.0
"""How often a render process checks that the process that started it is alive."""


def _exit_with_parent(parent: int) -> None:
    """A render process's initializer: exit when the server that started it is gone (a
    SIGKILLed server leaves no render processes behind)."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_POLL_S)
        os._exit(0)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


class RenderBackend(Protocol):
    """Where recipes are rendered."""

    @property
    def capacity(self) -> int:
        """Renders that may run at once."""
        ...

    def submit(self, recipe: bytes, clip: bool) -> "Future[RenderedMedia]":
        """Start rendering `recipe` (`render_recipe_bytes`); the future holds the bytes."""
        ...

    def warm(self, recipe: bytes) -> None:
        """Start the render processes and make their env for `recipe`'s settings, without
        waiting."""
        ...

    def start(self) -> None:
        """Start the render processes and load the renderer in them, without waiting."""
        ...

    def close(self) -> None: ...


class ProcessBackend:
    """`workers` spawn processes of this process (spawn: numba's and MuJoCo's threads and GL
    contexts do not survive a fork); restarted if one dies."""

    def __init__(self, workers: int = 2) -> None:
        if workers < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self._workers = workers
        self._executor: ProcessPoolExecutor | None = None
        self._lock = threading.Lock()

    @property
    def capacity(self) -> int:
        return self._workers

    def _pool(self) -> ProcessPoolExecutor:
        with self._lock:
            if self._executor is None:
                self._executor = ProcessPoolExecutor(
                    max_workers=self._workers,
                    mp_context=multiprocessing.get_context("spawn"),
                    initializer=_exit_with_parent,
                    initargs=(os.getpid(),),
                )
            return self._executor

    def submit(self, recipe: bytes, clip: bool) -> "Future[RenderedMedia]":
        try:
            return self._pool().submit(render_recipe_bytes, recipe, clip)
        except BrokenProcessPool:
            self._restart()
            return self._pool().submit(render_recipe_bytes, recipe, clip)

    def warm(self, recipe: bytes) -> None:
        for _ in range(self._workers):
            self._pool().submit(warm_recipe_env, recipe)

    def start(self) -> None:
        for _ in range(self._workers):
            self._pool().submit(load_renderer)

    def _restart(self) -> None:
        with self._lock:
            broken, self._executor = self._executor, None
        if broken is not None:
            broken.shutdown(wait=False, cancel_futures=True)

    def close(self) -> None:
        with self._lock:
            executor, self._executor = self._executor, None
        if executor is not None:
            executor.shutdown(wait=True, cancel_futures=True)


class RayBackend:
    """Renders as Ray tasks of one CPU each, on the cluster at `address` (joined here unless
    this process is already connected; None: a local Ray), at most `capacity` at a time
    (default: the cluster's CPUs when joined). The tasks import groupwise on the cluster's
    nodes, so each node needs it installed (with MuJoCo and an offscreen GL)."""

    def __init__(self, address: str | None, capacity: int | None = None) -> None:
        import ray

        self._ray = ray
        self._started = False
        if not ray.is_initialized():
            ray.init(address=address, logging_level=logging.WARNING, log_to_driver=False)
            self._started = True
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self._capacity = max(1, capacity if capacity is not None else cpus)
        self._render = ray.remote(num_cpus=1, max_retries=1)(render_recipe_bytes)
        self._warm = ray.remote(num_cpus=1)(warm_recipe_env)

    @property
    def capacity(self) -> int:
        return self._capacity

    def submit(self, recipe: bytes, clip: bool) -> "Future[RenderedMedia]":
        future: Future[RenderedMedia] = self._render.remote(recipe, clip).future()
        return future

    def warm(self, recipe: bytes) -> None:
        self._warm.remote(recipe)

    def start(self) -> None:
        """Nothing to start: the cluster's workers are Ray's."""

    def close(self) -> None:
        if self._started:
            self._ray.shutdown()
            self._started = False


class _Flight:
    """One id's render: the recipe, and the future every request for the id waits on."""

    def __init__(self, clip_id: str, recipe: bytes) -> None:
        self.clip_id = clip_id
        self.recipe = recipe
        self.done: Future[None] = Future()


class OnDemandClips:
    """Stored files of a clip store, rendered from their recipes when first asked for
    (module docstring)."""

    def __init__(self, store: ClipStore, backend: RenderBackend) -> None:
        self.store = store
        self.backend = backend
        self._lock = threading.Lock()
        self._flights: dict[str, _Flight] = {}
        self._waiting: list[_Flight] = []  # a stack: the newest is rendered next
        self._running = 0
        self._warmed = False
        self.rendered = 0
        """Renders finished (clips and posters), for tests and benchmarks."""

    async def file(self, clip_id: str) -> Path:
        """The file of `clip_id` in the store, rendered from its recipe first if needed.

        Raises:
            InvalidClipIdError: not a well-formed id.
            ClipNotFoundError: neither a file nor a recipe under this id.
            RenderBusyError: dropped from a full queue, or not rendered in time.
            RenderFailedError: rendering failed (nothing was stored).
        """
        recipe = self.store.recipe(clip_id)
        if clip_id in self.store:
            if recipe is not None:
                self._warm(recipe)
            return self.store.path(clip_id)
        if recipe is None:
            raise ClipNotFoundError(clip_id)
        done = self._join(clip_id, recipe)
        try:
            # shielded: a request that gives up (timeout, client gone) leaves the render to
            # the other requests for the id
            await asyncio.wait_for(asyncio.shield(asyncio.wrap_future(done)), RENDER_TIMEOUT_S)
        except TimeoutError:
            late = f"{clip_id} was not rendered within {RENDER_TIMEOUT_S:g} s"
            raise RenderBusyError(late) from None
        return self.store.path(clip_id)

    def close(self) -> None:
        with self._lock:
            dropped, self._waiting = self._waiting, []
        for flight in dropped:
            self._fail(flight, RenderBusyError("the server is stopping"))
        self.backend.close()

    def _warm(self, recipe: Path) -> None:
        """Start the render processes the first time a page looks at an on-demand round."""
        if self._warmed:
            return
        self._warmed = True
        try:
            self.backend.warm(recipe.read_bytes())
        except Exception:  # only a head start: a render will say what is wrong
            log.warning("could not warm the clip renderers", exc_info=True)

    def _join(self, clip_id: str, recipe: Path) -> "Future[None]":
        with self._lock:
            flight = self._flights.get(clip_id)
            if flight is not None:
                return flight.done
            if clip_id in self.store:  # rendered since the caller looked
                stored: Future[None] = Future()
                stored.set_result(None)
                return stored
            flight = self._flights[clip_id] = _Flight(clip_id, recipe.read_bytes())
            self._waiting.append(flight)
            dropped = self._waiting[:-MAX_WAITING] if len(self._waiting) > MAX_WAITING else []
            del self._waiting[: len(dropped)]
        for old in dropped:
            self._fail(old, RenderBusyError(f"{old.clip_id}: too many clips asked for at once"))
        self._dispatch()
        return flight.done

    def _dispatch(self) -> None:
        while True:
            with self._lock:
                if self._running >= self.backend.capacity or not self._waiting:
                    return
                flight = self._waiting.pop()
                self._running += 1
            try:
                future = self.backend.submit(flight.recipe, clip=flight.clip_id.endswith(".mp4"))
            except Exception as error:
                self._finished(flight, None, error)
                continue
            future.add_done_callback(functools.partial(self._landed, flight))

    def _landed(self, flight: _Flight, future: "Future[RenderedMedia]") -> None:
        self._finished(flight, future, None)

    def _finished(
        self, flight: _Flight, future: "Future[RenderedMedia] | None", error: BaseException | None
    ) -> None:
        try:
            if error is None and future is not None:
                error = future.exception()
            if error is None and future is not None:
                self._store(flight.clip_id, future.result())
                with self._lock:
                    self.rendered += 1
                    self._flights.pop(flight.clip_id, None)
                flight.done.set_result(None)
            else:
                log.error("could not render %s: %s", flight.clip_id, error)
                reason = f"{flight.clip_id} could not be rendered: {type(error).__name__}: {error}"
                self._fail(flight, RenderFailedError(reason))
        except Exception as failure:  # storing failed (disk full, …)
            reason = f"{flight.clip_id} could not be stored: {failure}"
            self._fail(flight, RenderFailedError(reason))
        finally:
            with self._lock:
                self._running -= 1
            self._dispatch()

    def _store(self, clip_id: str, media: RenderedMedia) -> None:
        key, suffix = clip_id.rsplit(".", 1)
        poster_suffix = suffix if suffix != "mp4" else _poster_suffix(media.poster)
        # the poster first: a stored clip implies its poster
        self.store.put_as(media.poster, f"{key}.{poster_suffix}")
        if media.clip is not None:
            self.store.put_as(media.clip, f"{key}.mp4")

    def _fail(self, flight: _Flight, error: RenderFailedError) -> None:
        with self._lock:
            self._flights.pop(flight.clip_id, None)
        if not flight.done.done():
            flight.done.set_exception(error)


def _poster_suffix(image: bytes) -> str:
    """ "png" or "jpg", from the image's first bytes."""
    return "png" if image.startswith(b"\x89PNG") else "jpg"


def local_renderer(store: ClipStore, workers: int = 2) -> OnDemandClips:
    """On-demand clips of `store` rendered by `workers` spawn processes of this process."""
    return OnDemandClips(store, ProcessBackend(workers))


def ray_renderer(
    store: ClipStore, address: str | None, capacity: int | None = None
) -> OnDemandClips:
    """On-demand clips of `store` rendered as Ray tasks (`RayBackend`; `capacity` renders at
    a time, default the cluster's CPUs)."""
    return OnDemandClips(store, RayBackend(address, capacity))
