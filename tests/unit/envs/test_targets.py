"""Target envs: hand-made MuJoCo states score as the case studies define, the env pays no
reward, and the simulated decision-makers prefer what scores higher."""

import math
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest

from groupwise.behaviour.pool import BehaviourPool
from groupwise.clips.timing import default_clip_seconds
from groupwise.envs import (
    ENVS,
    TARGET_ENVS,
    TARGET_SCORE_KEY,
    TARGET_TOTAL_KEY,
    TARGETS,
    TRUE_REWARD_KEY,
    BodyState,
    horizon,
    make_env,
    make_standard_env,
    resolve_id,
)
from groupwise.envs.scorers import upness, wrap_angle
from groupwise.episodes.fragments import Trajectory, tile_fragments
from groupwise.query.strategies import GroupSuggestions, InteractiveWalk, PairwiseQueries, Query
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.rollout import sample_trajectories
from groupwise.teachers import Feedback, PairwiseTeacher, Perception, SimulatedTeacher


@pytest.fixture(scope="module")
def hopper() -> Iterator[gym.Env]:
    env = make_env("Hopper-backflip")
    env.reset(seed=0)
    yield env
    env.close()


def _state(env: gym.Env, qpos: np.ndarray, com_height: float | None = None) -> BodyState:
    """The state at `qpos` (at rest), raised or lowered so that the centre of mass is at
    `com_height` when given."""
    base = env.unwrapped
    qpos = np.array(qpos, dtype=np.float64)
    base.set_state(qpos, np.zeros(base.model.nv))
    if com_height is not None:
        qpos[1] += com_height - BodyState.read(base).com_height
        base.set_state(qpos, np.zeros(base.model.nv))
    return BodyState.read(base)


def _on_floor(env: gym.Env, qpos: np.ndarray, lift: float = 0.0) -> BodyState:
    """The state at `qpos` moved up or down until its lowest capsule is `lift` m up."""
    base = env.unwrapped
    qpos = np.array(qpos, dtype=np.float64)
    base.set_state(qpos, np.zeros(base.model.nv))
    qpos[1] += lift - min(BodyState.read(base).bottoms.values())
    base.set_state(qpos, np.zeros(base.model.nv))
    return BodyState.read(base)


def _pitched(env: gym.Env, pitches: np.ndarray, com_height: float) -> list[BodyState]:
    qpos = env.unwrapped.init_qpos.copy()
    states = []
    for pitch in pitches:
        qpos[2] = pitch
        states.append(_state(env, qpos, com_height))
    return states


# ---------------------------------------------------------------- registration and the env


def test_target_envs_are_registered_beside_the_six() -> None:
    assert set(TARGET_ENVS) == {"Hopper-backflip", "HalfCheetah-standup", "Walker2d-splits"}
    assert not set(TARGET_ENVS) & set(ENVS)
    for target in TARGETS.values():
        assert target.env in TARGET_ENVS and target.base in ENVS
        assert resolve_id(target.env) == f"groupwise/{target.env}-v0"
        assert resolve_id(target.env) in gym.registry
        assert horizon(target.env) == 1000
        assert 0 < target.threshold < target.stretch
        # the success phrase states the threshold a score is judged by
        assert f"≥ {target.threshold:g}" in target.success
        assert make_standard_env(target.env).spec.id == resolve_id(target.env)
        # behaviours last as long as the base env's (the app's and case study's default)
        assert default_clip_seconds(target.env) == default_clip_seconds(target.base) == 1.5


@pytest.mark.parametrize("name", sorted(TARGET_ENVS))
def test_target_env_pays_nothing_and_reports_its_score(name: str) -> None:
    env = make_env(name)
    env.reset(seed=0)
    env.action_space.seed(0)
    scores = []
    for t in range(1, 1001):
        _, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert reward == 0.0 and terminated is False and truncated is (t == 1000)
        assert info[TRUE_REWARD_KEY] == info[TARGET_SCORE_KEY]
        scores.append(info[TARGET_SCORE_KEY])
    assert any(scores) or name == "HalfCheetah-standup"  # a random cheetah never stands
    target = next(t for t in TARGETS.values() if t.env == name)
    assert info[TARGET_TOTAL_KEY] < target.threshold  # the random baseline fails


def test_backflip_env_total_is_its_step_scores_times_dt() -> None:
    env = make_env("Hopper-backflip")
    env.reset(seed=3)
    env.action_space.seed(3)
    total = 0.0
    for _ in range(300):
        info = env.step(env.action_space.sample())[4]
        total += info[TARGET_SCORE_KEY] * env.unwrapped.dt / (2 * math.pi)
    assert info[TARGET_TOTAL_KEY] == pytest.approx(total)


@pytest.mark.parametrize("name", sorted(TARGET_ENVS))
def test_target_env_renders(name: str) -> None:
    env = make_env(name, render_mode="rgb_array", width=64, height=48)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    frame = env.render()
    assert frame.shape == (48, 64, 3) and frame.std() > 5.0
    env.close()


# ---------------------------------------------------------------- the hopper's backflip


def test_positive_pitch_tips_the_top_forward(hopper: gym.Env) -> None:
    base = hopper.unwrapped
    qpos = base.init_qpos.copy()
    qpos[2] = 0.5
    base.set_state(qpos, np.zeros(base.model.nv))
    axis = base.data.xmat[base.model.body("torso").id].reshape(3, 3)[:, 2]  # torso's "up"
    assert axis[0] > 0.4  # leaning towards +x, the hopper's forward


def test_one_backward_turn_up_in_the_air_is_one_flip(hopper: gym.Env) -> None:
    target, dt = TARGETS["hopper-backflip"], hopper.unwrapped.dt
    backward = _pitched(hopper, np.linspace(0.0, -2 * math.pi, 101), com_height=1.5)
    assert target.episode_score(backward, dt) == pytest.approx(1.0)
    steps = target.step_scores(backward, dt)
    assert steps.shape == (100,) and steps.sum() * dt == pytest.approx(2 * math.pi)
    assert steps == pytest.approx(2 * math.pi / (100 * dt))  # rad/s, every step
    assert target.succeeds(target.episode_score(backward, dt))


def test_forward_turn_counts_minus_one_and_two_turns_count_two(hopper: gym.Env) -> None:
    target, dt = TARGETS["hopper-backflip"], hopper.unwrapped.dt
    forward = _pitched(hopper, np.linspace(0.0, 2 * math.pi, 101), com_height=1.5)
    assert target.episode_score(forward, dt) == pytest.approx(-1.0)
    double = _pitched(hopper, np.linspace(0.0, -4 * math.pi, 201), com_height=1.5)
    assert target.episode_score(double, dt) == pytest.approx(2.0)
    assert target.stretches(target.episode_score(double, dt))
    assert not target.succeeds(target.episode_score(double[:100], dt))


def test_wrapped_pitches_unwrap_to_the_same_turns(hopper: gym.Env) -> None:
    target, dt = TARGETS["hopper-backflip"], hopper.unwrapped.dt
    wrapped = [wrap_angle(p) for p in np.linspace(0.0, -2 * math.pi, 101)]
    assert max(wrapped) - min(wrapped) > 6.0  # the sequence jumps from −π to π
    states = _pitched(hopper, np.array(wrapped), com_height=1.5)
    assert target.episode_score(states, dt) == pytest.approx(1.0)


def test_rolling_on_the_floor_is_no_flip(hopper: gym.Env) -> None:
    target, dt = TARGETS["hopper-backflip"], hopper.unwrapped.dt
    roll = _pitched(hopper, np.linspace(0.0, -2 * math.pi, 101), com_height=0.3)
    assert target.episode_score(roll, dt) == 0.0
    assert not target.step_scores(roll, dt).any()


# ---------------------------------------------------------------- the cheetah stands and sits


@pytest.fixture(scope="module")
def cheetah() -> Iterator[gym.Env]:
    env = make_env("HalfCheetah-standup")
    env.reset(seed=0)
    yield env
    env.close()


def _standing(env: gym.Env) -> BodyState:
    qpos = env.unwrapped.init_qpos.copy()
    qpos[2] = -math.pi / 2  # front straight up
    qpos[3] = math.radians(60)  # back thigh under the body
    return _on_floor(env, qpos)


def _lying(env: gym.Env) -> BodyState:
    return _on_floor(env, env.unwrapped.init_qpos.copy())


def test_standing_on_the_back_legs_is_up_lying_and_sitting_are_not(cheetah: gym.Env) -> None:
    standing = _standing(cheetah)
    assert standing.bottoms["torso"] > 0.3 and upness(standing) == 1.0
    assert upness(_lying(cheetah)) == 0.0
    sitting = cheetah.unwrapped.init_qpos.copy()
    sitting[2] = -math.pi / 2  # front up, rear on the floor
    assert upness(_on_floor(cheetah, sitting)) < 0.2
    toppled = cheetah.unwrapped.init_qpos.copy()
    toppled[2] = -math.radians(160)  # over onto its back
    toppled[3] = math.radians(60)
    assert upness(_on_floor(cheetah, toppled, lift=0.3)) == 0.0


def test_stand_and_sit_counts_a_cycle(cheetah: gym.Env) -> None:
    target, dt = TARGETS["halfcheetah-standup"], cheetah.unwrapped.dt
    up, down = _standing(cheetah), _lying(cheetah)
    once = [down] * 11 + [up] * 20 + [down] * 10  # 1 s up
    score = target.episode_score(once, dt)
    assert score == pytest.approx(1 + 0.5 * 20 / 40)  # one cycle + half the mean upness
    assert target.threshold <= score < target.stretch
    steps = target.step_scores(once, dt)
    # the sit that completes the cycle: 1.5 s of full standing (60° = π/3 rad a step)
    assert steps.max() == pytest.approx(math.pi / 3 * 1.5 / dt)
    thrice = [down] + ([up] * 12 + [down] * 8) * 3
    assert target.episode_score(thrice, dt) == pytest.approx(3 + 0.5 * 36 / 60)
    assert target.stretches(target.episode_score(thrice, dt))


def test_standing_alone_or_briefly_is_no_cycle(cheetah: gym.Env) -> None:
    target, dt = TARGETS["halfcheetah-standup"], cheetah.unwrapped.dt
    up, down = _standing(cheetah), _lying(cheetah)
    forever = target.episode_score([down] + [up] * 40, dt)
    assert forever == pytest.approx(0.5) and not target.succeeds(forever)
    brief = [down] + [up] * 5 + [down] * 5  # 0.25 s up: a wobble
    assert target.episode_score(brief, dt) == pytest.approx(0.25)
    assert target.episode_score([down] + [up] * 39 + [down], dt) == pytest.approx(1 + 0.5 * 39 / 40)


def test_wobbling_between_thresholds_completes_nothing(cheetah: gym.Env) -> None:
    target, dt = TARGETS["halfcheetah-standup"], cheetah.unwrapped.dt
    half = cheetah.unwrapped.init_qpos.copy()
    half[2] = -math.radians(45)  # front half raised: upness between the thresholds
    half[3] = math.radians(60)
    middle = _on_floor(cheetah, half)
    assert 0.2 < upness(middle) < 0.8
    wobble = [_lying(cheetah)] + [_standing(cheetah), middle] * 30
    assert target.episode_score(wobble, dt) < 1.0


# ---------------------------------------------------------------- the walker's splits


@pytest.fixture(scope="module")
def walker() -> Iterator[gym.Env]:
    env = make_env("Walker2d-splits")
    env.reset(seed=0)
    yield env
    env.close()


def _walker(env: gym.Env, pitch: float, right: float, left: float) -> BodyState:
    """Degrees: torso pitch, right and left thigh; feet tilted to meet the floor."""
    qpos = env.unwrapped.init_qpos.copy()
    qpos[2], qpos[3], qpos[6] = math.radians(pitch), math.radians(right), math.radians(left)
    qpos[5] = qpos[8] = math.radians(45)
    return _on_floor(env, qpos)


def test_a_split_held_for_a_second_succeeds(walker: gym.Env) -> None:
    target, dt = TARGETS["walker-splits"], walker.unwrapped.dt
    split = _walker(walker, -45, 0, -90)
    assert max(split.bottoms["foot_geom"], split.bottoms["foot_left_geom"]) < 0.01
    start = _walker(walker, 0, 0, 0)
    held = [start] + [split] * 125  # 1 s at 125 steps/s
    assert target.episode_score(held, dt) == pytest.approx(1.0)
    assert target.step_scores(held, dt)[-1] == pytest.approx(math.pi / 2)  # 90°, all down
    assert target.episode_score([start] + [split] * 124, dt) < target.threshold
    wider = _walker(walker, -55, 0, -110)  # no more than the split: it is the most a step pays
    assert target.step_scores([start, wider], dt)[0] == pytest.approx(math.pi / 2)


def test_fallen_or_one_footed_splits_score_below_the_threshold(walker: gym.Env) -> None:
    target, dt = TARGETS["walker-splits"], walker.unwrapped.dt
    start = _walker(walker, 0, 0, 0)
    fallen = _walker(walker, -90, 0, -90)  # legs apart, lying on its back
    assert target.step_scores([start, fallen], dt)[0] == pytest.approx(0.0)
    assert target.episode_score([start] + [fallen] * 500, dt) == 0.0
    one_foot = _walker(walker, 45, 0, -90)  # leaning forwards, the left leg up behind
    assert target.step_scores([start, one_foot], dt)[0] == pytest.approx(math.pi / 4)
    assert target.episode_score([start] + [one_foot] * 500, dt) == 0.0
    narrow = _walker(walker, -20, 0, -40)
    assert target.episode_score([start] + [narrow] * 500, dt) == 0.0


# ---------------------------------------------------------------- simulated teachers


@pytest.fixture(scope="module")
def backflip_episodes() -> list[Trajectory]:
    make = lambda: make_env("Hopper-backflip")  # noqa: E731
    policy = RandomPolicy(make().action_space)
    return sample_trajectories(make, policy, 6, np.random.default_rng(0))


@pytest.fixture(scope="module")
def backflip_pool(backflip_episodes: list[Trajectory]) -> BehaviourPool:
    """Random-policy behaviours of the backflip env: their true returns are target scores."""
    fragments = tuple(tile_fragments(backflip_episodes, 25))
    return BehaviourPool(0, fragments, np.random.default_rng(1).normal(size=(len(fragments), 3)))


def test_sampled_true_rewards_are_the_target_scores(backflip_episodes: list[Trajectory]) -> None:
    env = make_env("Hopper-backflip")
    for episode in backflip_episodes:
        env.reset(seed=episode.reset_seed)
        scores = [env.step(action)[4][TARGET_SCORE_KEY] for action in episode.actions]
        np.testing.assert_allclose(episode.true_rewards, scores)
        turns = env.step(episode.actions[0])[4][TARGET_TOTAL_KEY]  # one step past the end
        turned = episode.true_rewards.sum() * env.unwrapped.dt / (2 * math.pi)
        assert turned == pytest.approx(turns, abs=0.05)
    env.close()


def test_random_backflip_behaviours_differ_in_score(backflip_pool: BehaviourPool) -> None:
    # backward falls, forward falls, standing still: the teachers have something to tell
    assert backflip_pool.true_returns.std() > 0.5


@pytest.mark.parametrize(
    "feedback",
    [
        Feedback(PairwiseQueries(), PairwiseTeacher(sigma=0.0)),
        Feedback(GroupSuggestions(), SimulatedTeacher(Perception(sigma=0.0))),
        Feedback(InteractiveWalk(), SimulatedTeacher(Perception(sigma=0.0))),
    ],
    ids=["pairwise", "groupwise", "interactive"],
)
def test_simulated_teachers_prefer_the_higher_target_score(
    backflip_pool: BehaviourPool, feedback: Feedback
) -> None:
    judgements = feedback.gather(backflip_pool, 20, np.random.default_rng(2))
    returns = backflip_pool.true_returns
    preferences = [j for j in judgements if j.label != 0.5]
    assert preferences
    for j in preferences:
        better, worse = (j.left, j.right) if j.label == 1.0 else (j.right, j.left)
        assert returns[list(better)].min() > returns[list(worse)].max()
    for j in judgements:  # "equal" only for equal scores (most random hoppers lie still)
        assert j.label != 0.5 or np.ptp(returns[[*j.left, *j.right]]) == 0.0


def test_noisy_teacher_errs_as_the_noise_model_says(backflip_pool: BehaviourPool) -> None:
    returns, noise_sd = backflip_pool.true_returns, 25 * 0.25  # L·σ (SPEC §7)
    moderate = np.flatnonzero((returns > noise_sd) & (returns < 2 * noise_sd))
    assert moderate.size  # a backward lean, one to two noise sds above lying still
    chosen, still = int(moderate[0]), np.flatnonzero(returns == 0.0)[:200]
    queries = [Query((chosen,), (int(i),)) for i in still]
    teacher = SimulatedTeacher(Perception(sigma=0.25))
    judgements = teacher.answer(backflip_pool, queries, np.random.default_rng(3))
    right = np.mean([j.label == 1.0 for j in judgements])
    # P(right) = Φ(gap / (√2 · noise sd)): both perceived returns carry their own noise
    expected = 0.5 * (1 + math.erf(returns[chosen] / (2 * noise_sd)))
    assert len(judgements) == len(queries) and right == pytest.approx(expected, abs=0.08)
