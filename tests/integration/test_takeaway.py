"""The take-away agent on GridWorld: the package holds the chosen round's policy (issue 20)."""

import io
import json
import zipfile

import numpy as np
import pytest
import torch
from stable_baselines3 import PPO

from groupwise.agent_file.summary import AGENT_ZIP, read_summary
from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig
from groupwise.preferences.judgement import Judgement
from groupwise.run.agent_package import NoCheckpointError, UnknownRoundError, pick_round
from groupwise.run.headless import hand_over, run_session
from groupwise.run.run import Run
from groupwise.run.takeaway import TakeawayConfig, read_choice
from groupwise.teachers import DECISION_MAKERS, Feedback

TINY = RunConfig(
    loop=LoopConfig(
        env="GridWorld", comparisons=9, rounds=3, steps=3 * 256, eval_episodes=1, seed=5
    ),
    reward=RewardConfig(epochs=1, initial_epoch_multiplier=1),
    ppo=PPOConfig(n_envs=2, n_steps=128, batch_size=64, n_epochs=1, tensorboard=False),
)


class PrefersEarlier:
    """Prefers the behaviour earlier in the pool: the take-away pool lists round 0 first."""

    def answer(self, pool, queries, rng):
        return [Judgement(q.left, q.right, 1.0 if q.left[0] < q.right[0] else 0.0) for q in queries]


def _weights(policy_zip: bytes) -> dict[str, torch.Tensor]:
    return PPO.load(io.BytesIO(policy_zip), device="cpu").policy.state_dict()


def _zipped_policy(out) -> bytes:
    with zipfile.ZipFile(out / AGENT_ZIP) as archive:
        return archive.read("policy.zip")


def _same(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> bool:
    return a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("takeaway")
    run_session(TINY, out, show_progress=False, takeaway=TakeawayConfig(episodes=1))
    return out


def test_train_hands_over_the_teachers_round_and_records_it(run_dir):
    choice = read_choice(run_dir)
    assert choice is not None and choice.by == "teacher" and choice.rounds == (0, 1, 2)
    assert len(choice.verdicts) == 3  # one episode a round, three pairs of rounds
    summary = read_summary(run_dir)
    assert summary is not None
    assert (summary.round, summary.chosen_by) == (choice.round, "teacher")
    checkpoint = run_dir / "checkpoints" / f"round-{choice.round:04d}" / "policy.zip"
    assert _same(_weights(_zipped_policy(run_dir)), _weights(checkpoint.read_bytes()))
    saved = json.loads((run_dir / "takeaway.json").read_text())
    assert saved["config"] == {"by": "teacher", "episodes": 1}


def test_the_package_holds_the_chosen_rounds_weights_not_the_last(run_dir):
    with Run.create(TINY, run_dir) as run:
        run.restore()
        feedback = Feedback(DECISION_MAKERS["pairwise"](TINY).queries, PrefersEarlier())
        choice = hand_over(run, feedback, TakeawayConfig(episodes=2))
    assert choice.round == 0 and choice.scores[0] == 1.0
    packed = _weights(_zipped_policy(run_dir))
    first = _weights((run_dir / "checkpoints" / "round-0000" / "policy.zip").read_bytes())
    last = _weights((run_dir / "checkpoints" / "round-0002" / "policy.zip").read_bytes())
    assert _same(packed, first)
    assert not _same(packed, last)
    summary = read_summary(run_dir)
    assert summary is not None and summary.round == 0
    assert summary.env_steps == run.records[0].env_steps

    # a person picks round 1 instead (the app's results page)
    picked = pick_round(run_dir, 1)
    assert (picked.round, picked.chosen_by) == (1, "person")
    second = _weights((run_dir / "checkpoints" / "round-0001" / "policy.zip").read_bytes())
    assert _same(_weights(_zipped_policy(run_dir)), second)
    with pytest.raises(UnknownRoundError):
        pick_round(run_dir, 7)
    (run_dir / "checkpoints" / "round-0000" / "policy.zip").unlink()
    with pytest.raises(NoCheckpointError, match=r"round 0.s checkpoint has no policy\.zip"):
        pick_round(run_dir, 0)
    assert read_summary(run_dir).round == 1  # a refused pick changes nothing
    np.testing.assert_equal(summary.last_round, 2)
