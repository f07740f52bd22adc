"""The headless RLHF loop on GridWorld: rounds, results, checkpoints and exact resume."""

import csv
import dataclasses

import numpy as np
import pytest
import torch

from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig
from groupwise.run.headless import run_session
from groupwise.run.progress import OnRoundEnd
from groupwise.run.records import RoundRecord
from groupwise.run.run import RESULTS_FILE

TINY = RunConfig(
    loop=LoopConfig(
        env="GridWorld", comparisons=12, rounds=3, steps=3 * 256, eval_episodes=2, seed=3
    ),
    reward=RewardConfig(epochs=2, initial_epoch_multiplier=2),
    ppo=PPOConfig(n_envs=2, n_steps=128, batch_size=64, n_epochs=2, tensorboard=False),
)

TIMINGS = {"sample_s", "feedback_s", "reward_s", "ppo_s", "eval_s"}


def _without_timings(records: list[RoundRecord]) -> list[dict]:
    """The records minus wall times, with nan as None so that equal rows compare equal."""
    return [
        {
            key: None if isinstance(value, float) and np.isnan(value) else value
            for key, value in dataclasses.asdict(record).items()
            if key not in TIMINGS
        }
        for record in records
    ]


def test_session_writes_rounds_results_and_checkpoints(tmp_path):
    records = run_session(TINY, tmp_path, show_progress=False)
    assert [r.round for r in records] == [0, 1, 2]
    assert sum(r.comparisons for r in records) == 12
    # the pairwise DM gives one pair per comparison
    assert [r.pairs_total for r in records] == list(np.cumsum([r.pairs for r in records]))
    assert records[-1].pairs_total == 12
    assert all(0.0 <= r.label_error_rate_total <= 1.0 for r in records)
    assert records[-1].env_steps >= 3 * 256
    assert all(np.isfinite(r.true_return_mean) for r in records)

    with (tmp_path / RESULTS_FILE).open() as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["round"]) for r in rows] == [0, 1, 2]
    assert float(rows[-1]["true_return_mean"]) == pytest.approx(records[-1].true_return_mean)
    assert (tmp_path / "config.json").is_file()
    assert RunConfig.load(tmp_path / "config.json") == TINY
    for index in range(3):
        directory = tmp_path / "checkpoints" / f"round-{index:04d}"
        names = {p.name for p in directory.iterdir()}
        assert {"policy.zip", "reward.pt", "dataset.npz", "state.json"} <= names


class Killed(Exception):
    pass


def test_resume_after_a_crash_gives_the_same_results(tmp_path):
    straight = run_session(TINY, tmp_path / "straight", show_progress=False)

    def crash_after_first_round(record: RoundRecord) -> None:
        if record.round == 0:
            raise Killed

    with pytest.raises(Killed):
        run_session(
            TINY,
            tmp_path / "crashed",
            show_progress=False,
            callback=OnRoundEnd(crash_after_first_round),
        )
    resumed = run_session(TINY, tmp_path / "crashed", resume=True, show_progress=False)
    assert _without_timings(resumed) == _without_timings(straight)


def test_resume_refuses_a_different_configuration(tmp_path):
    run_session(
        dataclasses.replace(TINY, loop=dataclasses.replace(TINY.loop, rounds=1)),
        tmp_path,
        show_progress=False,
    )
    with pytest.raises(ValueError, match="different configuration"):
        run_session(TINY, tmp_path, resume=True, show_progress=False)


def test_a_pair_cap_keeps_one_pair_per_comparison(tmp_path):
    capped = dataclasses.replace(
        TINY,
        loop=dataclasses.replace(
            TINY.loop, decision_maker="groupwise", comparisons=24, pair_cap=1.0
        ),
    )
    records = run_session(capped, tmp_path, show_progress=False)
    assert all(r.pairs <= r.comparisons for r in records)
    assert records[-1].pairs_total > 0


def test_the_final_row_trains_ppo_on_the_frozen_reward(tmp_path):
    cfg = dataclasses.replace(TINY, loop=dataclasses.replace(TINY.loop, final_steps=256))
    records = run_session(cfg, tmp_path, show_progress=False)
    last, final = records[-2], records[-1]
    assert final.round == 3 and final.comparisons == 0 and final.pairs == 0
    assert final.pairs_total == last.pairs_total
    assert final.env_steps >= last.env_steps + 256
    assert np.isnan(final.reward_loss) and final.sample_s == 0.0 and final.reward_s == 0.0
    weights = [
        torch.load(tmp_path / "checkpoints" / f"round-{r:04d}" / "reward.pt", weights_only=True)
        for r in (2, 3)
    ]
    for name, tensor in weights[0]["state_dict"].items():
        assert torch.equal(tensor, weights[1]["state_dict"][name]), name
