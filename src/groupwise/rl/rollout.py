"""Sampling episodes from a policy, with random exploration mixed in (SPEC §3.1).

The episodes of a batch are stepped together, so the policy sees one batched observation per
step, but each episode runs until its own end: the env terminates it, truncates it (its time
limit), or it reaches `max_steps`. An env whose episode has ended is not stepped again and
the policy is asked only about the episodes still running. The groupwise envs have fixed
horizons, so there every episode of a batch has the same length; any other Gymnasium env
(e.g. ``Hopper-v5``, which ends when the hopper falls) gives episodes of their own lengths.

`sample_episodes_for_windows` samples as many episodes as it takes to tile a number of
L-step windows from them, whatever the episodes' lengths turn out to be. Sampling uses its own
env instances, never the ones PPO trains on. The envs of a large batch are stepped on the
free cores (`rl.batch_envs`: helper processes step shards of the batch in lock step), while
the policy and every random draw stay in this process, so the episodes do not depend on it.
"""

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.envs.episodes import GIVE_UP_EPISODES, too_short_message
from groupwise.envs.spaces import encode_actions
from groupwise.episodes.fragments import Trajectory
from groupwise.rl.batch_envs import BatchEnvs, processes_for
from groupwise.rl.policy import Policy, RowPolicy, random_actions
from groupwise.types import FloatArray, IntArray, ProgressFn

EnvFactory = Callable[[], gym.Env]

StepFn = Callable[[IntArray, IntArray], None]
"""(steps of each episode of a batch so far, indices of the episodes still running) -> None:
called after every step of a batch."""

EXPLORATION_SEGMENT = 10
"""Mean length in steps of one random-action stretch (the agent and the random policy take
turns in stretches, like imitation's ExplorationWrapper, so random behaviour is visible in a
clip rather than single jittered steps)."""


def exploration_mask(
    n_episodes: int, horizon: int, fraction: float, rng: np.random.Generator
) -> np.ndarray:
    """(n_episodes, horizon) bool mask of steps that take a random action.

    A two-state Markov switch whose stationary share of random steps is `fraction`, with
    random stretches of mean length `EXPLORATION_SEGMENT`. Column t is step t of each
    episode; the columns after an episode's end are not used.
    """
    if not 0.0 <= fraction < 1.0:
        raise ValueError(f"exploration fraction must be in [0, 1), got {fraction}")
    mask = np.zeros((n_episodes, horizon), dtype=bool)
    if fraction == 0.0:
        return mask
    leave_random = 1.0 / EXPLORATION_SEGMENT
    enter_random = fraction / (1.0 - fraction) * leave_random
    state = rng.random(n_episodes) < fraction
    draws = rng.random((n_episodes, horizon))
    for t in range(horizon):
        mask[:, t] = state
        switch = np.where(state, draws[:, t] < leave_random, draws[:, t] < enter_random)
        state = state ^ switch
    return mask


def sample_trajectories(
    make_env: EnvFactory,
    policy: Policy,
    n_episodes: int,
    rng: np.random.Generator,
    exploration_fraction: float = 0.0,
    max_steps: int | None = None,
    processes: int | None = None,
) -> list[Trajectory]:
    """Run `n_episodes` episodes of `policy` side by side and return them, numbered 0 … n − 1.

    Each episode lasts until the env terminates or truncates it, or for `max_steps` steps,
    whichever comes first, so episodes may differ in length. Each is reset with a seed drawn
    from `rng`, stored in the trajectory for replay. `processes`: how many processes step
    the envs (`rl.batch_envs`; None: the free cores for large batches); the episodes are the
    same whatever it is.

    Raises:
        ValueError: `n_episodes` < 1, or the env has no time limit (its spec sets no
            ``max_episode_steps``) and `max_steps` is not given.
    """
    if n_episodes < 1:
        raise ValueError(f"need at least one episode, got {n_episodes}")
    return _sample_batch(
        make_env, policy, n_episodes, rng, exploration_fraction, max_steps, 0, processes=processes
    )


def sample_episodes_for_windows(
    make_env: EnvFactory,
    policy: Policy,
    n_windows: int,
    length: int,
    rng: np.random.Generator,
    exploration_fraction: float = 0.0,
    batch: int | None = None,
    max_episodes: int | None = None,
    max_steps: int | None = None,
    progress: ProgressFn | None = None,
    snapshot_offsets: Sequence[int] = (),
    processes: int | None = None,
) -> list[Trajectory]:
    """Sample episodes until tiling them into `length`-step windows gives >= `n_windows`.

    The windows are those of `fragments.tile_fragments`: ``len(episode) // length`` per
    episode, none crossing an episode's end. Episodes are sampled in batches (see
    `sample_trajectories`); the first batch is sized as if every episode lasted the env's
    horizon (its time limit, or `max_steps` if smaller), ``ceil(n_windows / (horizon //
    length))`` episodes, which is all it takes for a fixed-horizon env; later batches are
    sized from the windows per episode seen so far. `batch` caps the episodes stepped side by
    side; `max_episodes` caps the episodes sampled in all, and when it stops the sampling the
    episodes may hold fewer than `n_windows` windows. The returned episodes are numbered
    0 … E − 1 across batches (pools key fragments by episode and start step).

    `progress` hears (steps sampled towards the windows, `n_windows` × `length`) as the
    steps are taken, never decreasing: an ended episode's steps count in whole windows, a
    running one's all (they may all become windows), at most the total.

    `snapshot_offsets` (steps into a window, each in [0, `length`)): for every window and
    offset o, the physics state before step ``start + o − 1`` goes into the episode's
    `Trajectory.snapshots` (MuJoCo envs; a window's frame o is rendered from it,
    `clips.recipe`).

    `processes` step each batch's envs (`rl.batch_envs.BatchEnvs`: this process and spawn
    helpers; None: `batch_envs.processes_for`, the free cores for large batches).
    The random draws all stay here, so the episodes and `rng`'s state afterwards are the
    same whatever it is.

    Raises:
        ValueError: a non-positive count; the env has no time limit and `max_steps` is not
            given; episodes cannot last `length` steps; or `GIVE_UP_EPISODES` episodes (or
            `max_episodes`, if fewer) hold no window at all (the message says how many steps
            they lasted).
    """
    for name, value in (("n_windows", n_windows), ("length", length)):
        if value < 1:
            raise ValueError(f"{name} must be >= 1, got {value}")
    for name, cap in (("batch", batch), ("max_episodes", max_episodes)):
        if cap is not None and cap < 1:
            raise ValueError(f"{name} must be >= 1 or None, got {cap}")
    probe = make_env()
    try:
        limit = _step_limit(probe, max_steps)
        env_name = _env_name(probe)
    finally:
        probe.close()
    if limit < length:
        raise ValueError(
            f"episodes of {env_name} last at most {limit} steps, fewer than one window of "
            f"{length} steps"
        )
    if any(not 0 <= o < length for o in snapshot_offsets):
        raise ValueError(f"snapshot offsets must lie in [0, {length}), got {snapshot_offsets}")
    snapshot_steps = frozenset(
        start + o - 1
        for start in range(0, limit - length + 1, length)
        for o in snapshot_offsets
        if start + o >= 1
    )
    trajectories: list[Trajectory] = []
    windows = 0
    target, reported = n_windows * length, 0

    def on_step(steps: IntArray, running: IntArray) -> None:
        nonlocal reported
        whole = steps // length * length
        whole[running] = steps[running]
        done = min(windows * length + int(whole.sum()), target)
        if progress is not None and done > reported:
            reported = done
            progress(done, target)

    if progress is not None:
        progress(0, target)
    wanted = math.ceil(n_windows / (limit // length))
    while windows < n_windows:
        room = math.inf if max_episodes is None else max_episodes - len(trajectories)
        if room <= 0:
            break
        size = int(min(wanted, batch or wanted, room))
        trajectories += _sample_batch(
            make_env,
            policy,
            size,
            rng,
            exploration_fraction,
            max_steps,
            len(trajectories),
            on_step if progress is not None else None,
            snapshot_steps,
            processes,
        )
        windows = sum(len(t) // length for t in trajectories)
        if windows == 0:
            if len(trajectories) >= min(GIVE_UP_EPISODES, max_episodes or math.inf):
                raise ValueError(
                    too_short_message(env_name, np.array([len(t) for t in trajectories]), length)
                )
            wanted = GIVE_UP_EPISODES - len(trajectories)
        else:
            wanted = math.ceil((n_windows - windows) * len(trajectories) / windows)
    return trajectories


@dataclass(frozen=True)
class Evaluation:
    """Whole episodes of a policy, measured (`evaluate_episodes`)."""

    returns: FloatArray  # (E,) true returns: each episode's per-step true rewards summed
    scores: FloatArray  # (E,) the env's episode scores (`Trajectory.episode_score`), nan: none


def evaluate_episodes(
    make_env: EnvFactory,
    policy: Policy,
    n_episodes: int,
    rng: np.random.Generator,
    max_steps: int | None = None,
) -> Evaluation:
    """The true return and the episode score (a target env's; nan for other envs) of each of
    `n_episodes` whole episodes of `policy`, each until its own end (`sample_trajectories`)."""
    trajectories = sample_trajectories(make_env, policy, n_episodes, rng, max_steps=max_steps)
    return Evaluation(
        returns=np.array([t.true_rewards.sum() for t in trajectories]),
        scores=np.array([t.episode_score for t in trajectories]),
    )


def evaluate(
    make_env: EnvFactory,
    policy: Policy,
    n_episodes: int,
    rng: np.random.Generator,
    max_steps: int | None = None,
) -> np.ndarray:
    """True (env) return of each of `n_episodes` whole episodes of `policy`, (n_episodes,).

    Each episode's return sums all its steps, until its own end (see `sample_trajectories`).
    """
    return evaluate_episodes(make_env, policy, n_episodes, rng, max_steps).returns


def _sample_batch(
    make_env: EnvFactory,
    policy: Policy,
    n_episodes: int,
    rng: np.random.Generator,
    exploration_fraction: float,
    max_steps: int | None,
    first_episode: int,
    on_step: StepFn | None = None,
    snapshot_steps: frozenset[int] = frozenset(),
    processes: int | None = 1,
) -> list[Trajectory]:
    probe = make_env()
    try:
        limit = _step_limit(probe, max_steps)
    finally:
        probe.close()
    with BatchEnvs(make_env, n_episodes, processes_for(n_episodes, limit, processes)) as envs:
        return _run(
            envs, policy, rng, exploration_fraction, limit, first_episode, on_step, snapshot_steps
        )


def _run(
    envs: BatchEnvs,
    policy: Policy,
    rng: np.random.Generator,
    exploration_fraction: float,
    limit: int,
    first_episode: int,
    on_step: StepFn | None = None,
    snapshot_steps: frozenset[int] = frozenset(),
) -> list[Trajectory]:
    space = envs.first.action_space
    n = envs.n
    seeds = rng.integers(0, 2**31 - 1, size=n)
    current = np.stack(envs.reset(seeds.tolist()))
    explore = exploration_mask(n, limit, exploration_fraction, rng)
    obs: list[list[np.ndarray]] = [[] for _ in range(n)]
    actions: list[list[Any]] = [[] for _ in range(n)]
    rewards: list[list[float]] = [[] for _ in range(n)]
    scores = np.full(n, np.nan)  # an env's episode score so far, where it has one
    snapshots: list[dict[int, FloatArray]] = [{} for _ in range(n)]  # step → state before it
    running = np.arange(n)  # the envs whose episodes have not ended, in order
    rows = policy if isinstance(policy, RowPolicy) else None
    for t in range(limit):
        batch = current.astype(np.float32)
        if rows is None:
            action = np.asarray(policy.act(batch, rng))
        else:  # policies side by side: each row's by its episode's number
            action = np.asarray(rows.act_rows(batch, first_episode + running, rng))
        random = explore[running, t]
        if random.any():
            action = action.copy()
            action[random] = random_actions(space, int(random.sum()), rng)
        indices = running.tolist()
        results = envs.step(indices, list(action), t in snapshot_steps)
        still, following = [], []
        for i, before, a, (after, reward, score, ended, state) in zip(
            indices, current, action, results, strict=True
        ):
            if state is not None:
                snapshots[i][t] = state
            obs[i].append(before)
            actions[i].append(a)
            rewards[i].append(reward)
            scores[i] = score
            if not ended:
                still.append(i)
                following.append(after)
        if on_step is not None:
            on_step(np.array([len(steps) for steps in obs]), np.array(still, dtype=np.int64))
        if not still:
            break
        running, current = np.array(still), np.stack(following)
    trajectories = []
    for i, seed in enumerate(seeds):
        steps = len(obs[i])
        raw = np.asarray(actions[i])
        trajectories.append(
            Trajectory(
                obs=np.asarray(obs[i]).reshape(steps, -1).astype(np.float32),
                acts=encode_actions(space, raw),
                actions=raw,
                true_rewards=np.asarray(rewards[i], dtype=np.float64),
                reset_seed=int(seed),
                episode=first_episode + i,
                episode_score=float(scores[i]),
                snapshots=snapshots[i],
            )
        )
    return trajectories


def _step_limit(env: gym.Env, max_steps: int | None) -> int:
    """Most steps an episode of `env` lasts: its time limit or `max_steps`, the smaller."""
    if max_steps is not None and max_steps < 1:
        raise ValueError(f"max_steps must be >= 1 or None, got {max_steps}")
    time_limit = env.spec.max_episode_steps if env.spec is not None else None
    if time_limit is None and max_steps is None:
        raise ValueError(
            f"env {_env_name(env)} has no fixed horizon (its registration sets no "
            "max_episode_steps), so an episode might never end: pass max_steps, or register "
            "the env with max_episode_steps"
        )
    return int(min(s for s in (time_limit, max_steps) if s is not None))


def _env_name(env: gym.Env) -> str:
    return env.spec.id if env.spec is not None else type(env.unwrapped).__name__
