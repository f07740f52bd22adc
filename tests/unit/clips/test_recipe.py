"""A clip rendered from its recipe (on demand, issue 22) is, bit for bit, the clip and poster
the pool's render job makes of the same window: from a physics snapshot (MuJoCo) or replayed
from the reset."""

import dataclasses
import io

import numpy as np
import pytest

from groupwise.clips.recipe import ClipRecipe, render_recipe, window_recipe
from groupwise.clips.render_jobs import plan_jobs, run_job
from groupwise.clips.replay import FrameSettings, ReplayMismatchError, make_render_env
from groupwise.clips.store import ClipStore
from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.envs import make_env
from groupwise.episodes.fragments import Fragment, Trajectory, tile_fragments
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.rollout import sample_episodes_for_windows

SIZE = 32


def _episode(env: str, length: int) -> tuple[Trajectory, list[Fragment], FrameSettings]:
    probe = make_env(env)
    timing = clip_timing(step_seconds(probe), steps=length)
    (episode, *_) = sample_episodes_for_windows(
        lambda: make_env(env),
        RandomPolicy(probe.action_space),
        1,
        length,
        np.random.default_rng(3),
        snapshot_offsets=timing.snapshot_offsets,
    )
    windows = tile_fragments([episode], length)
    chosen = [windows[0], windows[1], windows[len(windows) // 2], windows[-1]]
    return episode, chosen, FrameSettings(env, SIZE, SIZE)


@pytest.fixture(scope="module")
def hopper() -> tuple[Trajectory, list[Fragment], FrameSettings]:
    return _episode("Hopper", 40)  # 40 steps: 10 frames, a frame every 4th step


@pytest.mark.parametrize("env", ["Hopper", "GridWorld"])
def test_a_recipe_renders_the_clip_and_poster_of_the_render_job(tmp_path, env, hopper):
    episode, chosen, settings = hopper if env == "Hopper" else _episode(env, 30)
    timing = clip_timing(step_seconds(make_env(env)), steps=chosen[0].length)
    store = ClipStore(tmp_path)
    jobs = plan_jobs([episode], chosen, settings, workers=1, stride=timing.stride, fps=timing.fps)
    env_ = make_render_env(settings)
    eager = {c.start: c for job in jobs for c in run_job(job, store, env_).clips}
    for fragment in chosen:
        recipe = window_recipe(episode, fragment, settings, timing)
        # Hopper: every window but the first starts from a snapshot; GridWorld has none
        from_snapshot = env == "Hopper" and fragment.start > 0
        assert (recipe.origin > 0) == from_snapshot
        assert (recipe.poster_state.size > 0) == (env == "Hopper")
        media = render_recipe(recipe, env_)
        assert media.clip == store.path(eager[fragment.start].clip).read_bytes()
        assert media.poster == store.path(eager[fragment.start].poster).read_bytes()
        assert render_recipe(recipe, env_, clip=False) == dataclasses.replace(media, clip=None)


def test_without_snapshots_the_window_is_replayed_to_the_same_bytes(hopper):
    episode, chosen, settings = hopper
    timing = clip_timing(step_seconds(make_env("Hopper")), steps=chosen[0].length)
    bare = dataclasses.replace(episode, snapshots={})
    env = make_render_env(settings)
    late = chosen[-1]
    snapshot = window_recipe(episode, late, settings, timing)
    replayed = window_recipe(bare, late, settings, timing)
    assert (snapshot.origin, replayed.origin) == (late.start - 1, 0)
    assert snapshot.key != replayed.key
    assert render_recipe(snapshot, env) == render_recipe(replayed, env)


def test_a_recipe_survives_its_file_and_keys_its_contents(hopper):
    episode, chosen, settings = hopper
    timing = clip_timing(step_seconds(make_env("Hopper")), steps=chosen[0].length)
    recipe = window_recipe(episode, chosen[1], settings, timing)
    again = ClipRecipe.from_bytes(recipe.to_bytes())
    assert again.key == recipe.key and again.settings == recipe.settings
    assert recipe.clip_id() == f"{recipe.key}.mp4" and recipe.poster_id() == f"{recipe.key}.jpg"
    other = window_recipe(episode, chosen[2], settings, timing)
    assert other.key != recipe.key
    with np.load(io.BytesIO(recipe.to_bytes())) as arrays:
        fields = dict(arrays)
    fields["header"] = np.array(str(fields["header"]).replace("clip-recipe/1", "clip-recipe/9"))
    future = io.BytesIO()
    np.savez(future, **fields)
    with pytest.raises(ValueError, match="format"):
        ClipRecipe.from_bytes(future.getvalue())


@pytest.mark.parametrize("snapshots", [True, False])
def test_a_recipe_whose_steps_do_not_reproduce_is_refused(hopper, snapshots):
    episode, chosen, settings = hopper
    timing = clip_timing(step_seconds(make_env("Hopper")), steps=chosen[0].length)
    source = episode if snapshots else dataclasses.replace(episode, snapshots={})
    recipe = window_recipe(source, chosen[2], settings, timing)
    observations = recipe.observations.copy()
    observations[-3] += 0.1
    wrong = dataclasses.replace(recipe, observations=observations)
    with pytest.raises(ReplayMismatchError):
        render_recipe(wrong, make_render_env(settings))
