"""Each round trains on from the teacher's preferred policy so far (`run.keep`, issue 20)."""

import csv
import dataclasses
import io
import json

import pytest
import torch
from stable_baselines3 import PPO

from groupwise.cli import main
from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig, TrainingConfig
from groupwise.oracles import ORACLES, Feedback
from groupwise.preferences.judgement import Judgement
from groupwise.run.checkpoint import checkpoint_dir
from groupwise.run.headless import run_session
from groupwise.run.keep import keep_preferred
from groupwise.run.records import RoundRecord
from groupwise.run.run import Run

TINY = RunConfig(
    loop=LoopConfig(
        env="GridWorld", comparisons=12, rounds=4, steps=4 * 256, eval_episodes=1, seed=3
    ),
    reward=RewardConfig(epochs=1, initial_epoch_multiplier=1),
    ppo=PPOConfig(n_envs=2, n_steps=128, batch_size=64, n_epochs=1, tensorboard=False),
    training=TrainingConfig(continue_from="preferred", continue_episodes=2),
)


class ByPlace:
    """Prefers the behaviour earlier in the pool (`earlier`) or later: a keep choice's pool
    lists the earlier round's episodes first."""

    def __init__(self, earlier: bool) -> None:
        self.earlier = earlier

    def answer(self, pool, queries, rng):
        return [
            Judgement(q.left, q.right, float((q.left[0] < q.right[0]) == self.earlier))
            for q in queries
        ]


def _weights(path) -> dict[str, torch.Tensor]:
    return PPO.load(io.BytesIO(path.read_bytes()), device="cpu").policy.state_dict()


def _same(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> bool:
    return a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)


def _agent_weights(run: Run) -> dict[str, torch.Tensor]:
    return {k: v.clone() for k, v in run.ppo.model.policy.state_dict().items()}


def _policy(out, round_index: int) -> dict[str, torch.Tensor]:
    return _weights(checkpoint_dir(out, round_index) / "policy.zip")


def test_a_teacher_who_prefers_the_first_policy_keeps_it(tmp_path):
    feedback = Feedback(ORACLES["pairwise"](TINY).queries, ByPlace(earlier=True))
    records = run_session(TINY, tmp_path, show_progress=False, feedback=feedback)
    assert [r.continued_from for r in records] == [-1, 0, 0, 0]
    steps = [r.env_steps for r in records]
    assert steps == sorted(steps) and len(set(steps)) == 4  # PPO's step count goes on
    written = json.loads((checkpoint_dir(tmp_path, 3) / "state.json").read_text())
    assert [r["continued_from"] for r in written["records"]] == [-1, 0, 0, 0]


def test_the_preferred_policy_is_loaded_and_the_step_count_kept(tmp_path):
    cfg = dataclasses.replace(
        TINY, loop=dataclasses.replace(TINY.loop, rounds=2, steps=2 * 256, comparisons=6)
    )
    feedback = Feedback(ORACLES["pairwise"](cfg).queries, ByPlace(earlier=False))
    run_session(cfg, tmp_path, show_progress=False, feedback=feedback)
    first, second = _policy(tmp_path, 0), _policy(tmp_path, 1)
    assert not _same(first, second)
    with Run.create(cfg, tmp_path) as run:
        run.restore()
        steps = run.agent.num_timesteps
        assert keep_preferred(run, ByPlace(earlier=False)) == 1  # the last: nothing loaded
        assert run.continued_from == 1 and _same(_agent_weights(run), second)
        assert keep_preferred(run, ByPlace(earlier=True)) == 0
        assert run.continued_from == 0 and _same(_agent_weights(run), first)
        assert run.agent.num_timesteps == steps


def test_without_the_option_each_round_trains_on_from_the_last(tmp_path):
    cfg = dataclasses.replace(
        TINY,
        loop=dataclasses.replace(TINY.loop, rounds=3, steps=3 * 256, comparisons=9),
        training=TrainingConfig(),
    )
    feedback = Feedback(ORACLES["pairwise"](cfg).queries, ByPlace(earlier=True))
    records = run_session(cfg, tmp_path, show_progress=False, feedback=feedback)
    assert [r.continued_from for r in records] == [-1, 0, 1]


def _record(round_index: int, continued_from: int) -> RoundRecord:
    counts = ("comparisons", "judgements", "pairs", "pairs_total", "env_steps")
    measures = (
        "label_error_rate",
        "label_error_rate_total",
        "reward_loss",
        "reward_accuracy",
        "reward_val_accuracy",
        "true_return_mean",
        "true_return_std",
        "sample_s",
        "feedback_s",
        "reward_s",
        "ppo_s",
        "eval_s",
    )
    return RoundRecord(
        round=round_index,
        continued_from=continued_from,
        **dict.fromkeys(counts, 0),
        **dict.fromkeys(measures, float("nan")),
    )


def test_a_run_without_a_directory_cannot_go_back():
    with Run.create(TINY) as run:
        assert keep_preferred(run, ByPlace(earlier=True)) == -1  # no round yet
        run.records = [_record(0, -1)]
        assert keep_preferred(run, ByPlace(earlier=True)) == 0  # round 1: nothing to compare
        run.records.append(_record(1, 0))
        with pytest.raises(ValueError, match="no directory"):
            keep_preferred(run, ByPlace(earlier=True))


def test_the_cli_sets_it(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(
        [
            "train",
            "--env",
            "GridWorld",
            "--comparisons",
            "6",
            "--rounds",
            "3",
            "--steps",
            "384",
            "--continue-from",
            "preferred",
            "--out",
            str(out),
            "-q",
        ]
    )
    assert code == 0
    saved = json.loads((out / "config.json").read_text())
    assert saved["training"]["continue_from"] == "preferred"
    with (out / "rounds.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    first, second, third = (row["continued_from"] for row in rows)
    assert (first, second) == ("-1", "0") and third in ("0", "1")  # the teacher's choice
