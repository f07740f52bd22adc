"""Clips rendered on demand as Ray tasks (issue 22, item 7: ``groupwise serve --ray``) are the
clips rendered with the pool, bit for bit; on a local Ray of one CPU started here."""

import asyncio

import numpy as np
import pytest

from groupwise.clips.on_demand import ray_renderer
from groupwise.clips.store import ClipStore
from groupwise.pool.publish import PublishConfig, prepare_pool
from groupwise.rl.policy_files import load_policy


def test_clips_rendered_by_ray_tasks_are_the_eager_clips(tmp_path):
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install groupwise[ray])")
    store = ClipStore(tmp_path / "clips")
    pools = {}
    for clips in ("eager", "on_demand"):
        cfg = PublishConfig(env="Hopper", width=32, height=32, workers=0, clips=clips)
        policy = load_policy("random", "Hopper")
        rng = np.random.default_rng(11)  # the same behaviours both times
        out = tmp_path / clips
        pools[clips] = prepare_pool(
            cfg, policy, rng, out, size=4, length=40, store=store, show_progress=False
        )
    lazy = pools["on_demand"]
    assert not any(clip in store for clip in lazy.clips)
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)
    try:
        renderer = ray_renderer(store, address=None, capacity=1)

        async def ask() -> list:
            return await asyncio.gather(*(renderer.file(c) for c in lazy.clips))

        paths = asyncio.run(ask())
        renderer.close()
    finally:
        ray.shutdown()
    for path, eager in zip(paths, pools["eager"].clips, strict=True):
        assert path.read_bytes() == store.path(eager).read_bytes()
    assert renderer.rendered == 4
