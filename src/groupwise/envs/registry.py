"""The six groupwise envs, the three target envs, their Gymnasium registrations, and how to
make any env by name.

Every groupwise env has a fixed horizon and never terminates early (an episode's length must
not leak reward information, SPEC §2): ``terminated`` is always False and ``truncated`` is
True exactly at step `horizon`. The per-step true reward is the env's reward and is also in
``info["true_reward"]``. Ids live under the ``groupwise/`` namespace, e.g.
``groupwise/Hopper-v0``. The target envs (`TARGET_ENVS`, e.g. ``groupwise/Hopper-backflip-v0``)
are reward-free: their true reward is a case study's target score (`groupwise.envs.targets`).
`make_standard_env` gives the unmodified Gymnasium env for
evaluating a trained policy the way the rest of the field does. `make_env` also makes any
other Gymnasium env, by id or as ``"module:Env-v0"``; such envs may terminate early and may
have no time limit at all (`horizon` is then None). The DeepMind Control suite's
``dm_control/<domain>-<task>-v0`` ids (optional extra ``[dmc]``, `groupwise.envs.dmc`) get
their suite's fixed horizon. Dict and Tuple observations of Boxes are flattened into one
vector (`groupwise.envs.flatten`); any other non-Box observation space is refused by
`make_env` with one line (`groupwise.envs.spaces.observation_refusal`).
"""

import functools
import importlib
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

from groupwise.envs import dmc
from groupwise.envs.flatten import FlatObservation
from groupwise.envs.mujoco_log import log_mujoco_warnings
from groupwise.envs.rendering import OFFSCREEN_MODES, FastMujocoRendering, use_headless_sdl
from groupwise.envs.spaces import observation_refusal
from groupwise.envs.targets import TARGETS

NAMESPACE = "groupwise"


@dataclass(frozen=True)
class EnvEntry:
    """One groupwise env: how Gymnasium makes it and how it differs from the standard env."""

    name: str
    """Short name, e.g. "Hopper"; the Gymnasium id is ``groupwise/<name>-v0``."""
    entry_point: str
    """Gymnasium entry point, "module:callable"."""
    horizon: int
    """Steps per episode, always exactly this many."""
    standard_id: str | None
    """Gymnasium id of the unmodified env, or None when the env is our own."""
    changes: str
    """What differs from the standard env, for the docs."""
    clip_seconds: float | None = None
    """Simulated seconds a behaviour of the app covers (`groupwise.clips.timing`); None:
    the default, 1 s. Its clip plays at real speed."""

    @property
    def gym_id(self) -> str:
        """The id registered with Gymnasium."""
        return f"{NAMESPACE}/{self.name}-v0"

    def make(self, render_mode: str | None = None, **kwargs: Any) -> gym.Env[Any, Any]:
        """A fresh instance (`kwargs` go to the entry point, e.g. width, height)."""
        return gym.make(self.gym_id, render_mode=render_mode, **kwargs)


ENVS: dict[str, EnvEntry] = {
    entry.name: entry
    for entry in (
        EnvEntry(
            name="Hopper",
            entry_point="groupwise.envs.mujoco:make_hopper",
            horizon=1000,
            standard_id="Hopper-v5",
            changes="falling (unhealthy) does not terminate; 240×240 frames, torso-tracking camera",
            clip_seconds=1.5,  # 188 steps of 0.008 s: two hops, or a flip (30 were 0.24 s)
        ),
        EnvEntry(
            name="HalfCheetah",
            entry_point="groupwise.envs.mujoco:make_half_cheetah",
            horizon=1000,
            standard_id="HalfCheetah-v5",
            changes="none but rendering: 240×240 frames, torso-tracking camera",
            clip_seconds=1.5,  # 30 steps of 0.05 s: several strides, or a flip
        ),
        EnvEntry(
            name="Walker2d",
            entry_point="groupwise.envs.mujoco:make_walker2d",
            horizon=1000,
            standard_id="Walker2d-v5",
            changes="falling (unhealthy) does not terminate; 240×240 frames, torso-tracking camera",
            clip_seconds=1.5,  # 188 steps of 0.008 s: one to two strides, or a fall
        ),
        EnvEntry(
            name="Reacher",
            entry_point="groupwise.envs.mujoco:make_reacher",
            horizon=1000,
            standard_id="Reacher-v5",
            changes="horizon 1000 instead of 50; 240×240 frames",
            clip_seconds=1.0,  # 50 steps of 0.02 s: one reach, the standard Reacher-v5 episode
        ),
        EnvEntry(
            name="MountainCarContinuous",
            entry_point="groupwise.envs.mountain_car:DenseMountainCarEnv",
            horizon=250,
            standard_id="MountainCarContinuous-v0",
            changes=(
                "dense reward; reaching the goal does not terminate; horizon 250 instead of 999; "
                "240×240 frames"
            ),
            clip_seconds=2.0,  # 60 steps at 30 frames/s: a swing (crossing: >= 26 steps)
        ),
        EnvEntry(
            name="GridWorld",
            entry_point="groupwise.envs.gridworld:GridWorldEnv",
            horizon=1000,
            standard_id=None,
            changes="our own env (5×5, dense distance reward)",
            clip_seconds=1.0,  # 30 moves at its 30 frames/s, as in the study
        ),
    )
}
"""The groupwise envs by short name."""

_TARGET_MAKERS = {
    "hopper-backflip": "make_hopper_backflip",
    "halfcheetah-standup": "make_half_cheetah_standup",
    "walker-splits": "make_walker2d_splits",
}

TARGET_ENVS: dict[str, EnvEntry] = {
    target.env: EnvEntry(
        name=target.env,
        entry_point=f"groupwise.envs.targets:{_TARGET_MAKERS[name]}",
        horizon=ENVS[target.base].horizon,
        standard_id=None,
        clip_seconds=ENVS[target.base].clip_seconds,
        changes=(
            f"{target.base} with reward 0 and the {name} target score in "
            f'info["target_score"] and info["true_reward"]; no termination'
        ),
    )
    for name, target in TARGETS.items()
}
"""The case studies' target envs (`groupwise.envs.targets`) by short name, e.g.
"Hopper-backflip": reward-free, their true reward is the target's score."""


def env_entry(name: str) -> EnvEntry | None:
    """The `EnvEntry` of a short name in `ENVS` or `TARGET_ENVS`; None for any other name."""
    return ENVS.get(name) or TARGET_ENVS.get(name)


MUJOCO_MODULES = ("groupwise.envs.mujoco", "groupwise.envs.targets", "gymnasium.envs.mujoco")
"""Entry-point modules (and their sub-modules) of MuJoCo envs (`is_mujoco`)."""


def is_mujoco(name: str) -> bool:
    """Whether `name` is a MuJoCo env: a groupwise one made in `MUJOCO_MODULES` (Hopper,
    HalfCheetah, Walker2d, Reacher and the case studies' targets), a registered Gymnasium id
    made there (e.g. "Hopper-v5"), or a dm_control id; False for anything else, unknown
    names included (`recipes.Recipe.parts` reads it)."""
    if (entry := env_entry(name)) is not None:
        entry_point: object = entry.entry_point
    elif dmc.is_dmc_id(name):
        return True
    else:
        spec = gym.registry.get(name.partition(":")[2] or name)
        entry_point = None if spec is None else spec.entry_point
    module = entry_point.partition(":")[0] if isinstance(entry_point, str) else ""
    return any(module == m or module.startswith(m + ".") for m in MUJOCO_MODULES)


def register_envs() -> None:
    """Register every env in `ENVS` and `TARGET_ENVS` with Gymnasium; calling it again does
    nothing."""
    for entry in (*ENVS.values(), *TARGET_ENVS.values()):
        if entry.gym_id not in gym.registry:
            gym.register(
                id=entry.gym_id,
                entry_point=entry.entry_point,
                max_episode_steps=entry.horizon,
            )


def resolve_id(name: str) -> str:
    """The Gymnasium id for a short name in `ENVS` or `TARGET_ENVS`, a registered Gymnasium id, or
    ``"module:Env-v0"``, the form `gymnasium.make` accepts for an env that importing its
    module registers (the module is imported here, so the bare id it returns can be made).

    Raises:
        ValueError: `name` is none of these, its module cannot be imported, or importing it
            registers no such id.
    """
    if (entry := env_entry(name)) is not None:
        return entry.gym_id
    register_envs()
    if name in gym.registry:
        return name
    if dmc.is_dmc_id(name):  # Shimmy registers the suite when imported
        _import_registering_module(name, dmc.MODULE)
        if name in gym.registry:
            return name
        raise ValueError(f"unknown env {name!r}: {dmc.MODULE} registers no such dm_control id")
    module, colon, gym_id = name.partition(":")
    if colon and module and gym_id:
        _import_registering_module(name, module)
        if gym_id in gym.registry:
            return gym_id
        raise ValueError(f"env {name!r}: importing {module!r} registered no env {gym_id!r}")
    raise ValueError(
        f"unknown env {name!r}: use one of {', '.join([*ENVS, *TARGET_ENVS])}, a registered "
        "Gymnasium id, or 'module:Env-v0' for an env that importing its module registers"
    )


def _import_registering_module(name: str, module: str) -> None:
    """Import `module`, whose import registers env `name`. Raises ValueError when it cannot
    be imported (for Shimmy: naming the extra that installs it)."""
    if module == dmc.MODULE:
        dmc.prepare_import()
    try:
        importlib.import_module(module)
    except ImportError as error:
        if module == dmc.MODULE:
            raise ValueError(
                f"env {name!r} needs the DeepMind Control suite: pip install "
                f"'groupwise[{dmc.EXTRA}]' (shimmy[dm-control]); importing {module} failed "
                f"({error})"
            ) from None
        raise ValueError(f"env {name!r}: cannot import module {module!r} ({error})") from None
    if module == dmc.MODULE:
        dmc.after_import()


def make_env(name: str, render_mode: str | None = None, **kwargs: Any) -> gym.Env[Any, Any]:
    """Make an env by short name (see `ENVS`), registered Gymnasium id or ``"module:Env-v0"``
    (see `resolve_id`).

    Gymnasium MuJoCo envs that are not ours also get `FastMujocoRendering` (fixed camera)
    when rendered offscreen; for offscreen modes pygame is set up headless first
    (`use_headless_sdl`). `kwargs` go to the env's constructor (for ours: width, height; for
    the DeepMind Control suite they go to its renderer, `envs.dmc.make_kwargs`). A suite env
    gets its time limit as a ``TimeLimit`` (`envs.dmc.adapt`); a Dict or Tuple observation
    space is flattened into one Box (`envs.flatten.FlatObservation`).

    Raises:
        ValueError: unknown name (the message lists the known short names), a module that
            cannot be imported or does not register the id, or an observation space that
            cannot be taught (images, Discrete, Text…: one line that says why).
    """
    gym_id = resolve_id(name)
    log_mujoco_warnings()
    if render_mode in OFFSCREEN_MODES:
        use_headless_sdl()  # pygame-drawn envs (classic control) draw offscreen, quietly
    if dmc.is_dmc_id(gym_id):
        env = dmc.adapt(
            gym.make(gym_id, render_mode=render_mode, **dmc.make_kwargs(render_mode, kwargs))
        )
    else:
        env = gym.make(gym_id, render_mode=render_mode, **kwargs)
    return _with_fast_rendering(_with_flat_observations(env, name))


def _with_flat_observations(env: gym.Env[Any, Any], name: str) -> gym.Env[Any, Any]:
    """`env` as is when it observes a Box, flattened when a Dict or Tuple of Boxes.

    Raises:
        ValueError: any other observation space (`observation_refusal`'s reason); `env` is
            closed first.
    """
    space = env.observation_space
    if (reason := observation_refusal(space)) is not None:
        env.close()
        raise ValueError(f"env {name} cannot be taught here: {reason}")
    if isinstance(space, gym.spaces.Box):
        return env
    return FlatObservation(env)


def make_standard_env(
    name: str, render_mode: str | None = None, **kwargs: Any
) -> gym.Env[Any, Any]:
    """Make the standard Gymnasium env behind a short name, for evaluation as others report it.

    Hopper → ``Hopper-v5`` (terminates on a fall), Reacher → ``Reacher-v5`` (50 steps),
    MountainCarContinuous → ``MountainCarContinuous-v0`` (sparse reward, ends at the goal),
    and so on; its reward is the standard one and it puts nothing in ``info["true_reward"]``.
    GridWorld, being our own, is returned as in `make_env`; a Gymnasium id is made as is.

    Raises:
        ValueError: unknown name.
    """
    entry = ENVS.get(name)
    if entry is None or entry.standard_id is None:
        return make_env(name, render_mode=render_mode, **kwargs)
    if render_mode in OFFSCREEN_MODES:
        use_headless_sdl()
    env = gym.make(entry.standard_id, render_mode=render_mode, **kwargs)
    return _with_fast_rendering(env)


def horizon(name: str) -> int | None:
    """Most steps an episode of an env lasts, by short name, Gymnasium id or "module:id".

    Exact for the groupwise envs and the DeepMind Control suite's (its task's time limit in
    steps, `envs.dmc.suite_step_limit`: the env is made once per process to read it); for
    other ids it is the registered ``max_episode_steps``, and those envs may end earlier
    (terminate). None when there is no time limit: such an env can be sampled only for a
    given number of steps (`rl.rollout`'s `max_steps`).

    Raises:
        ValueError: unknown name.
    """
    if (entry := env_entry(name)) is not None:
        return entry.horizon
    gym_id = resolve_id(name)
    if dmc.is_dmc_id(gym_id):
        return _suite_horizon(gym_id)
    return gym.spec(gym_id).max_episode_steps


@functools.cache
def _suite_horizon(gym_id: str) -> int | None:
    env = gym.make(gym_id)
    try:
        return dmc.suite_step_limit(env)
    finally:
        env.close()


def _with_fast_rendering(env: gym.Env[Any, Any]) -> gym.Env[Any, Any]:
    if env.render_mode not in OFFSCREEN_MODES or not isinstance(env.unwrapped, MujocoEnv):
        return env
    layer: Any = env
    while isinstance(layer, gym.Wrapper):
        if isinstance(layer, FastMujocoRendering):
            return env
        layer = layer.env
    return FastMujocoRendering(env)
