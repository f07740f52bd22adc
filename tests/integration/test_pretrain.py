"""Unsupervised pre-training before round 0 (issue 20) on GridWorld: it trains the policy on
the state-entropy bonus, the rounds then run as usual, and a resumed run repeats it."""

import csv
import dataclasses

import numpy as np
import pytest
import torch

from groupwise.cli import main
from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig, TrainingConfig
from groupwise.run.headless import feedback_of, run_rounds, run_session
from groupwise.run.pretrain import (
    StateEntropyPretraining,
    before_first_round,
    pretrain,
    setup_hooks,
)
from groupwise.run.progress import OnRoundEnd, RunCallback
from groupwise.run.records import RoundRecord
from groupwise.run.run import Run

PRETRAIN_STEPS = 2048

TINY = RunConfig(
    loop=LoopConfig(
        env="GridWorld", comparisons=12, rounds=2, steps=2 * 256, eval_episodes=2, seed=5
    ),
    reward=RewardConfig(epochs=2, initial_epoch_multiplier=2),
    ppo=PPOConfig(n_envs=2, n_steps=128, batch_size=64, n_epochs=2, tensorboard=False),
    training=TrainingConfig(pretrain_steps=PRETRAIN_STEPS),
)
WITHOUT = dataclasses.replace(TINY, training=TrainingConfig())
TIMINGS = {"sample_s", "feedback_s", "reward_s", "ppo_s", "eval_s"}


def _parameters(run: Run) -> dict[str, torch.Tensor]:
    return {k: v.clone() for k, v in run.ppo.model.policy.state_dict().items()}


def _rows(records: list[RoundRecord]) -> list[dict]:
    return [
        {
            k: None if isinstance(v, float) and np.isnan(v) else v
            for k, v in dataclasses.asdict(r).items()
            if k not in TIMINGS
        }
        for r in records
    ]


def test_pretraining_trains_the_policy_and_then_the_rounds_run(tmp_path):
    with Run.create(TINY) as run:
        fresh = _parameters(run)
        report = pretrain(run)
        assert report is not None
        assert report.steps >= PRETRAIN_STEPS
        assert run.agent.num_timesteps == report.steps
        assert len(report.bonus_means) > 0
        trained = _parameters(run)
        actor = [k for k in fresh if k.startswith(("mlp_extractor.policy_net", "action_net"))]
        assert any(not torch.equal(fresh[k], trained[k]) for k in actor)
        records = run_rounds(run, feedback_of(TINY))
    assert [r.round for r in records] == [0, 1]
    assert records[0].env_steps >= PRETRAIN_STEPS + 256  # pre-training counts as PPO steps


def test_pretraining_is_the_same_for_a_seed():
    def pretrained() -> dict[str, torch.Tensor]:
        with Run.create(TINY) as run:
            pretrain(run)
            return _parameters(run)

    first, second = pretrained(), pretrained()
    assert all(torch.equal(first[k], second[k]) for k in first)


def test_pretraining_hands_over_at_the_action_noise_asked_its_mean_kept():
    """`teach_log_std` sets the policy's σ once pre-training ends; its greedy actions, what
    the person takes away, are those of the same pre-training without it."""
    cfg = dataclasses.replace(
        TINY,
        loop=dataclasses.replace(TINY.loop, env="Pendulum-v1"),
        training=TrainingConfig(pretrain_steps=256, teach_log_std=-2.0),
    )
    obs = np.random.default_rng(0).normal(size=(16, 3)).astype(np.float32)

    def pretrained(cfg: RunConfig) -> tuple[torch.Tensor, np.ndarray]:
        with Run.create(cfg) as run:
            pretrain(run)
            greedy = run.ppo.act(obs, np.random.default_rng(1), deterministic=True)
            return run.ppo.model.policy.log_std.detach().clone(), greedy

    noise, greedy = pretrained(cfg)
    left, greedy_left = pretrained(
        dataclasses.replace(cfg, training=TrainingConfig(pretrain_steps=256))
    )
    assert torch.equal(noise, torch.full_like(noise, -2.0))
    assert not torch.allclose(left, noise)  # pre-training alone leaves σ near 1
    np.testing.assert_array_equal(greedy, greedy_left)
    with Run.create(dataclasses.replace(TINY, training=cfg.training)) as run:
        with pytest.raises(ValueError, match="continuous actions"):
            pretrain(run)  # GridWorld's actions are discrete


def test_no_pretraining_by_default_and_none_after_round_0():
    with Run.create(WITHOUT) as run:
        assert pretrain(run) is None
        assert run.agent.num_timesteps == 0
    with Run.create(TINY) as run:
        run.records.append(None)  # type: ignore[arg-type]  # a run already at round 1
        with pytest.raises(ValueError, match="before round 0"):
            pretrain(run)
    with Run.create(TINY) as run:
        pretrain(run)
        with pytest.raises(ValueError, match="before round 0"):
            pretrain(run)  # once is all


def test_pretraining_is_a_setup_hook_run_once_on_a_fresh_run():
    assert setup_hooks(WITHOUT) == ()
    assert setup_hooks(TINY) == (StateEntropyPretraining(PRETRAIN_STEPS, k=5, states=10_000),)

    class Counted:
        def __init__(self) -> None:
            self.runs = 0

        def before_first_round(self, run: Run, callback: RunCallback) -> None:
            self.runs += 1

    hook = Counted()
    with Run.create(WITHOUT) as run:
        assert before_first_round(run, hooks=[hook]) and hook.runs == 1
        run.agent.learn(256, 0)  # an agent that has trained is not fresh: nothing runs
        assert not before_first_round(run, hooks=[hook]) and hook.runs == 1
    with Run.create(TINY) as run:
        assert before_first_round(run)  # the config's hooks: pre-training
        assert run.agent.num_timesteps >= PRETRAIN_STEPS


def test_a_pretrained_run_differs_from_one_without(tmp_path):
    pre = run_session(TINY, tmp_path / "pre", show_progress=False)
    plain = run_session(WITHOUT, tmp_path / "plain", show_progress=False)
    assert pre[0].env_steps == plain[0].env_steps + PRETRAIN_STEPS
    assert _rows(pre) != _rows(plain)


class Killed(Exception):
    pass


class _KillAtFirstPPO(RunCallback):
    """Dies in round 0's PPO: after pre-training, before anything was committed."""

    def on_phase(self, phase: str, done: int, total: int) -> None:
        if phase == "ppo":
            raise Killed


def test_resume_repeats_a_pretrained_run_exactly(tmp_path):
    straight = run_session(TINY, tmp_path / "straight", show_progress=False)

    def crash_after_round_0(record: RoundRecord) -> None:
        if record.round == 0:
            raise Killed

    with pytest.raises(Killed):
        run_session(
            TINY, tmp_path / "after", show_progress=False, callback=OnRoundEnd(crash_after_round_0)
        )
    resumed = run_session(TINY, tmp_path / "after", resume=True, show_progress=False)
    assert _rows(resumed) == _rows(straight)

    with pytest.raises(Killed):
        run_session(TINY, tmp_path / "before", show_progress=False, callback=_KillAtFirstPPO())
    again = run_session(TINY, tmp_path / "before", resume=True, show_progress=False)
    assert _rows(again) == _rows(straight)


def test_the_command_line_asks_for_pretraining(tmp_path):
    out = tmp_path / "train"
    args = ["--comparisons", "4", "--rounds", "1", "--steps", "0", "--seed", "1", "-q"]
    code = main(
        ["train", "--env", "GridWorld", "--pretrain-steps", "512", "--out", str(out), *args]
    )
    assert code == 0
    assert RunConfig.load(out / "config.json").training.pretrain_steps == 512
    with (out / "rounds.csv").open() as handle:
        (row,) = csv.DictReader(handle)
    assert int(row["env_steps"]) >= 512  # one whole rollout of pre-training, no PPO after
