"""Recorded datasets as episodes to label (issue 42): Minari datasets and D4RL-style HDF5.

A dataset is named by a reference (`open_dataset`):

- ``minari:<id>``: a dataset already in the local Minari store (``MINARI_DATASETS_PATH``,
  else ``~/.minari/datasets``); groupwise never downloads one;
- a directory: a Minari dataset's own directory (the one holding ``data/``, or ``data/``);
- a ``.hdf5`` / ``.h5`` file in D4RL's layout: ``observations`` (N, d), ``actions`` (N, a),
  ``rewards`` (N,), ``terminals`` and ``timeouts`` (N,) ending episodes (an episode ends
  after the step where either is true), optionally ``infos/qpos`` and ``infos/qvel``
  (N, ·); the env's id in the root attribute ``env`` (else give it beside, ``--env``).

Each episode becomes a `Trajectory` (its observation before each step, its actions and
rewards). Clips are drawn from MuJoCo physics states (`RecordedStates`):

- stored ones, where the dataset has ``qpos`` and ``qvel`` per step (Minari ``infos``,
  D4RL ``infos/``);
- else rebuilt from the observation, for the Gymnasium MuJoCo envs whose observation is
  ``qpos[1:]`` then ``qvel`` (Hopper, Walker2d and HalfCheetah v5): qpos[0], the x
  position the observation leaves out, is integrated from 0 by the trapezoid rule,
  x_{t+1} = x_t + dt × (qvel_t[0] + qvel_{t+1}[0]) / 2 (dt the env's control step).
  Against a rerun's x: the reset's own x noise (uniform ±0.005 m on Hopper and Walker2d,
  ±0.1 m on HalfCheetah) plus the drift of the integration, measured on random-action
  episodes (5 seeds): Hopper at most 0.4 mm over 73 steps, Walker2d 0.8 mm over 57 steps,
  HalfCheetah 0.14 m over 200 steps (its contacts change the velocity within a control
  step; the rectangle rule x_{t+1} = x_t + dt × qvel_{t+1}[0] drifts 5-10 times more on
  Hopper and Walker2d). Hopper's and Walker2d's observations clip the velocity at ±10, so a
  faster stretch drifts more. Every other part of the state is the observation's own, so
  the body's pose is exact and only the floor under it (the camera follows the body) is
  shifted by that much: `tests/unit/pool/test_dataset.py` compares a rebuilt-state clip's
  first frame with a rerun's. Any other observation needs stored states
  (`check_dataset_env` refuses it without them).

Rendering from states draws each frame from its own state (`clips.recipe`), never steps
the physics, so no replay has to agree with the recording.
"""

import functools
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.envs.physics_state import physics_state
from groupwise.types import FloatArray

MINARI = "minari:"
HDF5_SUFFIXES = (".hdf5", ".h5")


class DatasetError(ValueError):
    """A dataset that cannot be read or labelled here; its message is one line for a person."""


@dataclass(frozen=True)
class RecordedEpisode:
    """One recorded episode: T steps."""

    obs: FloatArray  # (T, obs_dim) observation before each step
    actions: np.ndarray  # (T, act_dim) the actions taken
    rewards: FloatArray  # (T,) the dataset's rewards
    qpos: FloatArray | None = None  # (T, nq) stored positions before each step, when held
    qvel: FloatArray | None = None  # (T, nv)

    def __len__(self) -> int:
        return int(self.obs.shape[0])


@dataclass(frozen=True)
class RecordedDataset:
    """A dataset's episodes and the env they were recorded in."""

    reference: str
    env: str | None  # the Gymnasium id the dataset names (None: it names none)
    episodes: tuple[RecordedEpisode, ...]

    @property
    def steps(self) -> int:
        return sum(len(e) for e in self.episodes)

    @property
    def has_states(self) -> bool:
        return all(e.qpos is not None and e.qvel is not None for e in self.episodes)


def open_dataset(reference: str) -> RecordedDataset:
    """The dataset named by `reference` (module docstring), read whole (cached per process).

    Raises:
        DatasetError: no such dataset, Minari or h5py missing, or a layout it cannot read.
    """
    try:
        return _open(_normalised(reference), str(minari_store()))
    except DatasetError:
        raise
    except (OSError, ValueError) as error:  # a path the OS refuses (too long, a NUL byte)
        raise DatasetError(f"dataset {reference[:200]!r} cannot be read: {error}") from None


def _normalised(reference: str) -> str:
    if reference.startswith(MINARI):
        return reference
    return str(Path(reference).expanduser().resolve())


@functools.lru_cache(maxsize=2)
def _open(reference: str, store: str) -> RecordedDataset:
    """The dataset `reference` (a minari:<id> of the store `store`, or an absolute path)."""
    if reference.startswith(MINARI):
        return _minari(reference, reference.removeprefix(MINARI), None)
    path = Path(reference)
    if path.is_file() and path.suffix in HDF5_SUFFIXES:
        return _hdf5(reference, path)
    if path.is_dir():
        return _minari(reference, None, path / "data" if (path / "data").is_dir() else path)
    raise DatasetError(
        f"dataset {reference}: no such Minari dataset directory or .hdf5 file "
        "(a dataset of the local Minari store is minari:<id>)"
    )


def minari_store() -> Path:
    """The local Minari store: ``MINARI_DATASETS_PATH``, else ``~/.minari/datasets``."""
    return Path(os.environ.get("MINARI_DATASETS_PATH", "~/.minari/datasets")).expanduser()


def _minari(reference: str, dataset_id: str | None, path: Path | None) -> RecordedDataset:
    try:
        from minari.dataset.minari_dataset import MinariDataset
    except ImportError:
        raise DatasetError(
            f"dataset {reference}: Minari is not installed (pip install 'groupwise[minari]')"
        ) from None
    if dataset_id is not None:  # read from the store's own layout: <id>/data (Minari's
        # lookups would make the store's directory as a side effect)
        path = minari_store() / dataset_id / "data"
        named = Path(dataset_id)
        if named.is_absolute() or ".." in named.parts or not path.is_dir():
            raise DatasetError(
                f"dataset {dataset_id} is not in the local Minari store ({minari_store()}); "
                f"groupwise never downloads: run `minari download {dataset_id}` first"
            )
    assert path is not None
    try:
        dataset = MinariDataset(path)
    except Exception as error:  # Minari's own errors: a missing or broken metadata file
        raise DatasetError(f"dataset {reference}: Minari cannot read it: {error}") from None
    spec = dataset.spec.env_spec
    episodes = tuple(_minari_episode(reference, e) for e in dataset.iterate_episodes())
    return _checked(RecordedDataset(reference, None if spec is None else spec.id, episodes))


def _minari_episode(reference: str, episode: Any) -> RecordedEpisode:
    obs, actions = episode.observations, np.asarray(episode.actions)
    if not isinstance(obs, np.ndarray) or obs.ndim != 2 or actions.ndim != 2:
        raise DatasetError(
            f"dataset {reference}: only vector observations and actions can be labelled here "
            f"(episode {episode.id} has {type(obs).__name__} observations)"
        )
    steps = len(actions)
    infos = episode.infos if isinstance(episode.infos, dict) else {}
    qpos, qvel = infos.get("qpos"), infos.get("qvel")
    return RecordedEpisode(
        obs=np.asarray(obs[:steps], dtype=np.float64),
        actions=actions,
        rewards=np.asarray(episode.rewards, dtype=np.float64),
        qpos=None if qpos is None else np.asarray(qpos[:steps], dtype=np.float64),
        qvel=None if qvel is None else np.asarray(qvel[:steps], dtype=np.float64),
    )


def _hdf5(reference: str, path: Path) -> RecordedDataset:
    try:
        import h5py
    except ImportError:
        raise DatasetError(
            f"dataset {reference}: h5py is not installed (pip install h5py)"
        ) from None
    try:
        with h5py.File(path, "r") as f:
            obs = np.asarray(f["observations"], dtype=np.float64)
            actions = np.asarray(f["actions"])
            rewards = np.asarray(f["rewards"], dtype=np.float64).reshape(-1)
            ends = np.zeros(len(obs), dtype=bool)
            for name in ("terminals", "timeouts"):
                if name in f:
                    ends |= np.asarray(f[name]).reshape(-1).astype(bool)
            qpos = np.asarray(f["infos/qpos"], np.float64) if "infos/qpos" in f else None
            qvel = np.asarray(f["infos/qvel"], np.float64) if "infos/qvel" in f else None
            env = f.attrs.get("env")
    except KeyError as error:
        raise DatasetError(f"dataset {reference}: not in D4RL's layout: {error}") from None
    except OSError as error:
        raise DatasetError(
            f"dataset {reference}: not an HDF5 file h5py can read: {error}"
        ) from None
    if obs.ndim != 2 or actions.ndim != 2 or not len(obs) == len(actions) == len(rewards):
        raise DatasetError(
            f"dataset {reference}: observations {obs.shape}, actions {actions.shape} and "
            f"rewards {rewards.shape} must be N rows of vectors"
        )
    ends[-1] = True
    bounds = np.flatnonzero(ends) + 1
    episodes, start = [], 0
    for end in bounds:
        part = slice(start, int(end))
        episodes.append(
            RecordedEpisode(
                obs[part],
                actions[part],
                rewards[part],
                None if qpos is None else qpos[part],
                None if qvel is None else qvel[part],
            )
        )
        start = int(end)
    name = env.decode() if isinstance(env, bytes) else env
    return _checked(
        RecordedDataset(reference, None if name is None else str(name), tuple(episodes))
    )


def _checked(dataset: RecordedDataset) -> RecordedDataset:
    if not dataset.episodes or dataset.steps == 0:
        raise DatasetError(f"dataset {dataset.reference} holds no steps")
    return dataset


def check_dataset_env(dataset: RecordedDataset, env: gym.Env[Any, Any], name: str) -> None:
    """Check that `env` (made as `name`) can show `dataset`: its observation and action
    vectors have the dataset's sizes, and its clips can be drawn from physics states
    (stored, or rebuilt: `RecordedStates`).

    Raises:
        DatasetError: a size differs, or no state can be had.
    """
    first = dataset.episodes[0]
    obs_size = int(np.prod(env.observation_space.shape or (0,)))
    act_size = int(np.prod(env.action_space.shape or (0,)))
    if (obs_size, act_size) != (first.obs.shape[1], first.actions.shape[1]):
        raise DatasetError(
            f"dataset {dataset.reference} has observations of {first.obs.shape[1]} and actions "
            f"of {first.actions.shape[1]} values; env {name} has {obs_size} and {act_size}"
        )
    if dataset.has_states:
        return
    model = getattr(env.unwrapped, "model", None)
    if model is None or obs_size != model.nq - 1 + model.nv:
        raise DatasetError(
            f"dataset {dataset.reference} stores no qpos/qvel, and env {name}'s observation "
            "is not qpos[1:] and qvel (Hopper, Walker2d, HalfCheetah v5): its clips cannot be "
            "drawn"
        )


@dataclass(frozen=True, eq=False)
class RecordedStates(Mapping[int, FloatArray]):
    """Step t → the MuJoCo integration state (S,) before step t of a recorded episode, made
    when asked from its qpos and qvel (stored, or rebuilt from the observation:
    `rebuilt_positions`) on a cached env of `env` (reset, the positions and velocities set,
    `physics_state`). A trajectory whose snapshots are these is drawn frame by frame from
    them (`clips.recipe.window_recipe`)."""

    env: str
    qpos: FloatArray  # (T, nq)
    qvel: FloatArray  # (T, nv)

    def __getitem__(self, step: int) -> FloatArray:
        if not 0 <= step < len(self.qpos):
            raise KeyError(step)
        base = _state_env(self.env).unwrapped
        base.set_state(self.qpos[step], self.qvel[step])  # type: ignore[attr-defined]  # a MujocoEnv
        state = physics_state(base)
        assert state is not None
        return state

    def __iter__(self) -> Iterator[int]:
        return iter(range(len(self.qpos)))

    def __len__(self) -> int:
        return len(self.qpos)


@functools.cache
def _state_env(name: str) -> gym.Env[Any, Any]:
    from groupwise.envs.registry import make_env

    env = make_env(name)
    env.reset(seed=0)
    return env


def episode_states(episode: RecordedEpisode, env: str) -> RecordedStates:
    """The episode's physics states: stored, or rebuilt from its observations."""
    if episode.qpos is not None and episode.qvel is not None:
        return RecordedStates(env, episode.qpos, episode.qvel)
    base = _state_env(env).unwrapped
    model, dt = base.model, base.dt  # type: ignore[attr-defined]  # a MujocoEnv (as above)
    qpos, qvel = rebuilt_positions(episode.obs, model.nq, model.nv, dt)
    return RecordedStates(env, qpos, qvel)


def rebuilt_positions(
    obs: FloatArray, nq: int, nv: int, dt: float
) -> tuple[FloatArray, FloatArray]:
    """qpos (T, nq) and qvel (T, nv) from observations (T, ≥ nq − 1 + nv) that begin with
    qpos[1:] then qvel: qpos[0] integrated from 0 by the trapezoid rule (module docstring)."""
    qpos = np.empty((len(obs), nq))
    qpos[:, 1:] = obs[:, : nq - 1]
    qvel = np.array(obs[:, nq - 1 : nq - 1 + nv], dtype=np.float64)
    qpos[0, 0] = 0.0
    qpos[1:, 0] = np.cumsum(qvel[1:, 0] + qvel[:-1, 0]) * (dt / 2)
    return qpos, qvel
