"""Continuous training with a timed teacher on GridWorld (`groupwise.run.continuous`): PPO
runs while the teacher answers, the reward switches only between rollouts, and a seed's
run is the same wherever it runs."""

import dataclasses

import numpy as np
import pytest
import torch

from groupwise.cli import main
from groupwise.config import (
    LoopConfig,
    PPOConfig,
    RewardConfig,
    RunConfig,
    TeacherConfig,
    TrainingConfig,
)
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.rl.learned_reward import LearnedRewardVecEnv
from groupwise.run import continuous
from groupwise.run.continuous import GROUP_PAIRS_PER_COMPARISON, paper_pace
from groupwise.run.headless import run_session
from groupwise.run.progress import RunCallback
from groupwise.run.records import RoundRecord
from groupwise.run.run import RESULTS_FILE, Run

PACE, RATE = 2.0, 96.0  # 192 PPO steps per answer: one and a half rollouts
CONTINUOUS = RunConfig(
    loop=LoopConfig(
        env="GridWorld",
        decision_maker="groupwise",
        comparisons=16,
        rounds=2,
        eval_episodes=2,
        seed=5,
    ),
    teacher=TeacherConfig(pace_s=PACE),
    training=TrainingConfig(mode="continuous", ppo_steps_per_s=RATE, refit_pairs=6, refit_s=9),
    reward=RewardConfig(epochs=2, initial_epoch_multiplier=2),
    ppo=PPOConfig(n_envs=2, n_steps=64, batch_size=64, n_epochs=1, tensorboard=False),
)
ROLLOUT = 2 * 64
TIMINGS = {"sample_s", "feedback_s", "reward_s", "ppo_s", "eval_s"}


class _Fits(RunCallback):
    """Each reward fit's moment: the agent's PPO steps so far, the dataset's size."""

    def __init__(self) -> None:
        self.run: Run | None = None
        self.fits: list[tuple[int, int]] = []

    def on_phase(self, phase: str, done: int, total: int) -> None:
        if phase == "reward":
            assert self.run is not None
            self.fits.append((self.run.agent.num_timesteps, total))


def _run(tmp_path, cfg=CONTINUOUS, callback=None) -> list[RoundRecord]:
    return run_session(cfg, tmp_path, show_progress=False, callback=callback)


def _comparable(records: list[RoundRecord]) -> list[dict]:
    return [
        {k: v for k, v in dataclasses.asdict(r).items() if k not in TIMINGS and v == v}
        for r in records
    ]


def test_ppo_runs_while_the_teacher_answers_and_the_reward_changes_between_rollouts(tmp_path):
    fits = _Fits()
    original = Run.create

    def create(*args, **kwargs):  # hand the run to the callback, which reads its steps
        fits.run = original(*args, **kwargs)
        return fits.run

    # each PPO env step notes which fit of the reward model gave its reward
    fitted, seen = [0], []
    real_fit, real_step = continuous.fit, LearnedRewardVecEnv.step_wait

    def counted_fit(*args, **kwargs):
        report = real_fit(*args, **kwargs)
        fitted[0] += 1
        return report

    def noted_step(self):
        seen.append(fitted[0])
        return real_step(self)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Run, "create", create)
        patch.setattr(continuous, "fit", counted_fit)
        patch.setattr(LearnedRewardVecEnv, "step_wait", noted_step)
        records = _run(tmp_path, callback=fits)
    assert [r.round for r in records] == [0, 1]
    # the teacher's clock: every query of the round took PACE seconds
    asked = [r.queries_asked for r in records]
    assert records[0].clock_s == asked[0] * PACE
    assert records[1].clock_s == (asked[0] + asked[1]) * PACE
    # PPO ran on that clock, in whole rollouts, what was left under one rollout dropped; it
    # waited out round 0's last answer, while round 1's pool was cut (`cut_next`)
    steps_before = 0
    waits = [PACE, 0.0]
    for record, before, waited in zip(records, [0.0, records[0].clock_s], waits, strict=True):
        owed = (record.clock_s - before - waited) * RATE
        trained = record.env_steps - steps_before
        assert trained % ROLLOUT == 0 and owed - ROLLOUT < trained <= owed
        steps_before = record.env_steps
    # several fits a round, each on more pairs than the last, and a rollout's rewards all
    # from one fit: the reward changes only between rollouts (64 env steps of 2 envs)
    assert len(fits.fits) > 2 * len(records)
    rollouts = [seen[i : i + 64] for i in range(0, len(seen), 64)]
    assert len(seen) == records[-1].env_steps // 2
    assert all(len(set(rollout)) == 1 for rollout in rollouts)
    assert len({rollout[0] for rollout in rollouts}) > 2  # … and it did change between them
    sizes = [size for _, size in fits.fits]
    assert sizes == sorted(sizes) and sizes[0] > 0
    assert sizes[-1] == records[-1].pairs_total
    # the reward ensemble was fitted while PPO went on: steps were taken between fits
    assert len({steps for steps, _ in fits.fits}) > 2


def test_a_timed_teachers_run_is_the_same_for_a_seed(tmp_path):
    first = _run(tmp_path / "a")
    again = _run(tmp_path / "b")
    assert _comparable(first) == _comparable(again)
    a = PreferenceDataset.load(tmp_path / "a" / "checkpoints" / "round-0001" / "dataset.npz")
    b = PreferenceDataset.load(tmp_path / "b" / "checkpoints" / "round-0001" / "dataset.npz")
    assert np.array_equal(a.pairs, b.pairs) and np.array_equal(a.labels, b.labels)
    reward_a = torch.load(tmp_path / "a" / "checkpoints" / "round-0001" / "reward.pt")
    reward_b = torch.load(tmp_path / "b" / "checkpoints" / "round-0001" / "reward.pt")
    for name, tensor in reward_a["state_dict"].items():
        assert torch.equal(tensor, reward_b["state_dict"][name]), name


def test_rounds_with_a_timed_teacher_wait_for_ppo_on_the_clock(tmp_path):
    cfg = dataclasses.replace(
        CONTINUOUS,
        loop=dataclasses.replace(CONTINUOUS.loop, steps=2 * 256),
        training=dataclasses.replace(CONTINUOUS.training, mode="rounds"),
    )
    records = _run(tmp_path, cfg)
    first = records[0]
    assert first.clock_s == first.queries_asked * PACE + 256 / RATE
    assert records[1].clock_s == first.clock_s + records[1].queries_asked * PACE + 256 / RATE


def test_continuous_training_needs_a_timed_teacher_and_no_pair_cap(tmp_path):
    untimed = dataclasses.replace(CONTINUOUS, teacher=TeacherConfig())
    with pytest.raises(ValueError, match="timed teacher"):
        _run(tmp_path / "a", untimed)
    capped = dataclasses.replace(CONTINUOUS, loop=dataclasses.replace(CONTINUOUS.loop, pair_cap=1))
    with pytest.raises(ValueError, match="pair_cap"):
        _run(tmp_path / "b", capped)


def test_the_paper_pace_converts_pairs_to_comparisons():
    # hopper: 1,032 pairs in 34 min; a group comparison gives 2.71 pairs, a pairwise one 1
    assert paper_pace("hopper-backflip", pairwise=True) == pytest.approx(34 * 60 / 1032)
    assert paper_pace("hopper-backflip", pairwise=False) == pytest.approx(
        34 * 60 / 1032 * GROUP_PAIRS_PER_COMPARISON
    )
    assert paper_pace(None, pairwise=True) == pytest.approx(109 * 60 / 2249)


def test_train_continuous_from_the_command_line(tmp_path, capsys):
    args = ["train", "--env", "GridWorld", "--dm", "groupwise", "--comparisons", "8"]
    args += ["--rounds", "1", "--training", "continuous", "--teacher-pace", "0.5", "-q"]
    args += ["--teacher-error", "0.12"]
    assert main([*args, "--out", str(tmp_path)]) == 0
    saved = RunConfig.load(tmp_path / "config.json")
    assert (saved.training.mode, saved.teacher.pace_s) == ("continuous", 0.5)
    assert saved.teacher.label_error == 0.12
    assert "label_error_untied" in (tmp_path / RESULTS_FILE).read_text().splitlines()[0]
    assert main([*args[:-2], "--teacher-error", "0.7", "--out", str(tmp_path / "y")]) == 2
    assert "label_error" in capsys.readouterr().err
    with pytest.raises(SystemExit) as refused:
        main([*args[:-5], "-q", "--teacher-pace", "0", "--out", str(tmp_path / "x")])
    assert refused.value.code == 2
    assert "expected a finite number > 0" in capsys.readouterr().err


def test_a_continuous_round_refits_when_due_and_an_undo_counts(tmp_path):
    from groupwise.preferences.judgement import LEFT_BETTER, Judgement
    from groupwise.run.continuous import ContinuousRound
    from groupwise.run.pairs import derive_pairs
    from groupwise.run.round import begin_round
    from groupwise.run.streams import round_streams
    from groupwise.teachers import DECISION_MAKERS

    cfg = dataclasses.replace(
        CONTINUOUS,
        training=dataclasses.replace(CONTINUOUS.training, refit_pairs=4, refit_s=100.0),
    )
    with Run.create(cfg, None) as run:
        streams = round_streams(cfg.loop.seed, 0)
        offer = begin_round(run, DECISION_MAKERS["groupwise"](cfg).queries, 8, streams=streams)
        continuous = ContinuousRound(run, offer, streams, clock=0.0)
        a = Judgement((0, 1, 2), (3, 4), LEFT_BETTER)  # 3 pairs
        b = Judgement((5,), (6,), LEFT_BETTER)  # 1 pair
        assert continuous.update([(0, a)], clock=1.0)  # a run's first pairs: fitted at once
        assert len(run.dataset) == 3 and continuous.report is not None
        assert not continuous.update([(0, a), (1, b)], clock=2.0)  # 1 new pair < 4, 1 s < 100 s
        assert continuous.update([(0, a), (1, b)], clock=150.0)  # due by time
        assert len(run.dataset) == 4
        assert not continuous.update([(0, a), (1, b)], clock=500.0)  # nothing changed
        # b undone (1 pair) and nothing new: due only by time …
        assert not continuous.update([(0, a)], clock=151.0)
        assert continuous.update([(0, a)], clock=300.0)
        # … and the dataset is the rounds before plus the pairs of the judgements now
        assert len(run.dataset) == len(derive_pairs([a], cfg.loop, 0, [0])) == 3
        assert continuous.update([(0, a), (2, b)], clock=301.0, final=True)  # final: any change
        assert run.dataset.rounds.tolist() == [0] * 4
