"""A `groupwise train` run continued with more steps on the frozen reward, packed as
agent.zip and loaded back with `load_agent` (docs/library.md); what the summary, the README
and `evaluate` say a target env's agent scored (issue 23: its episode score in the
target's unit, the per-step sum beside it)."""

import json
import math
import zipfile
from dataclasses import asdict, replace

import numpy as np
import pytest

import groupwise
from groupwise.agent_file.readme import readme
from groupwise.agent_file.summary import AgentSummary, ObsNormalisation, TargetSummary, measure_of
from groupwise.agent_file.text import score_text
from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig
from groupwise.envs import TARGET_TOTAL_KEY, TARGETS, TRUE_REWARD_KEY, make_env
from groupwise.rl.rollout import evaluate_episodes
from groupwise.rl.trained_agent import TrainedAgent
from groupwise.run import agent_package
from groupwise.run.final import continue_run
from groupwise.run.headless import run_session
from groupwise.run.records import RoundRecord
from groupwise.run.round import train_frozen
from groupwise.run.run import Run
from groupwise.run.streams import eval_rng

TINY = RunConfig(
    loop=LoopConfig(
        env="GridWorld", comparisons=4, rounds=1, steps=64, final_steps=64, eval_episodes=1
    ),
    reward=RewardConfig(epochs=1, initial_epoch_multiplier=1),
    ppo=PPOConfig(n_envs=1, n_steps=32, batch_size=16, n_epochs=1, tensorboard=False),
)


def test_a_train_run_continues_and_loads_as_an_agent(tmp_path):
    run_session(TINY, tmp_path, show_progress=False)  # round 0, then the final row 1
    records = continue_run(tmp_path, steps=32, frame_size=32, show_progress=False)
    assert [r.round for r in records] == [0, 1, 2]
    assert records[2].comparisons == 0 and np.isnan(records[2].reward_loss)
    assert records[2].env_steps >= records[1].env_steps + 32

    names = set(zipfile.ZipFile(tmp_path / "agent.zip").namelist())
    assert {"README.md", "agent.json", "policy.zip", "vecnormalize.npz", "reward.pt"} <= names
    readme = zipfile.ZipFile(tmp_path / "agent.zip").read("README.md").decode()
    assert "groupwise.load_agent" in readme

    agent = groupwise.load_agent(tmp_path / "agent.zip")
    assert (agent.env, agent.summary.round) == ("GridWorld", 2)
    # the plan's final row and the continuation are rounds without feedback
    assert [r.feedback for r in agent.summary.rounds] == [True, False, False]
    obs, _ = agent.make_env().reset(seed=1)
    assert agent.predict(obs).shape == ()
    assert agent.predict(np.stack([obs] * 4)).shape == (4,)
    evaluation = agent.evaluate(episodes=2, seed=0)
    assert evaluation.returns.shape == (2,) and evaluation.scores is None
    assert str(evaluation).startswith("true return ")
    assert agent.config() == TINY
    assert all(math.isnan(r.target_score_mean) for r in records)  # GridWorld has no target
    assert agent.summary.target is None and agent.summary.target_score_mean is None


def test_continuing_needs_one_of_steps_and_rounds(tmp_path):
    with pytest.raises(ValueError, match="either steps or rounds"):
        continue_run(tmp_path, steps=1, rounds=1)
    with pytest.raises(ValueError, match="simulated decision-maker"):
        continue_run(tmp_path, rounds=1, decision_maker="human")


@pytest.mark.parametrize(
    ("env", "measure"),
    [
        ("GridWorld", "true return"),
        ("Hopper-backflip", "per-step score sum (rad/s)"),
        ("groupwise/Walker2d-splits-v0", "per-step score sum (rad)"),
    ],
)
def test_the_summary_names_what_it_measures(env, measure):
    assert measure_of(env) == measure


BACKFLIP = TargetSummary.of(TARGETS["hopper-backflip"])


def test_a_target_score_reads_in_the_targets_unit_beside_the_per_step_sum():
    # the numbers: 0.23 backward turns per episode, per-step sum 184 ± 2.62, the sd to
    # the mean's last place (issue 40)
    text = score_text(BACKFLIP, "per-step score sum (rad/s)", (184.3, 2.62), (0.2312, 0.05))
    assert text == (
        "backward turns per episode 0.231 ± 0.050 (threshold 1) · per-step sum 184 ± 3 rad/s"
    )
    assert score_text(BACKFLIP, "…", (184.3, 2.62)) == "per-step sum 184 ± 3 rad/s"
    assert score_text(None, "true return", (41.5, 3.2)) == "true return 41.5 ± 3.2"
    assert score_text(None, "true return", (None, None)) == "not measured"
    assert score_text(None, "true return", (0.14, 0.000621)) == "true return 0.140 ± 0.001"


def record(round_index, true_return, score):
    """A round's row with only what the summary reads set."""
    nan = math.nan
    return RoundRecord(
        round_index, 2, 2, 4, 4 * (round_index + 1), nan, nan, nan, nan, nan,
        64 * (round_index + 1), true_return, 2.62, 0, 0, 0, 0, 0,
        target_score_mean=score, target_score_std=0.05,
    )  # fmt: skip


def summarise(cfg, records, frozen, video):
    normalised = ObsNormalisation(normalize_obs=True, clip_obs=5.0, epsilon=1e-6)
    return agent_package.summarise(cfg, records, frozen, video, normalisation=normalised)


def test_a_target_runs_summary_and_readme_lead_with_its_episode_score():
    cfg = RunConfig(loop=LoopConfig(env="Hopper-backflip"))
    summary = summarise(cfg, [record(0, 150.0, 0.19), record(1, 184.3, 0.2312)], {1}, None)
    assert summary.measure == "per-step score sum (rad/s)"
    assert (summary.target, summary.target_score_mean, summary.true_return_mean) == (
        BACKFLIP,
        0.2312,
        184.3,
    )
    assert [r.target_score_mean for r in summary.rounds] == [0.19, 0.2312]
    text = readme(summary)
    assert (
        "backward turns per episode 0.231 ± 0.050 (threshold 1) · per-step sum 184 ± 3 rad/s"
        in text
    )
    assert "hopper-backflip counts backward turns per episode; an episode succeeds from 1" in text
    assert "target score" not in text
    assert "+ 1e-06),\n                -5.0, 5.0)" in text  # the normalisation, as recorded
    again = AgentSummary.from_dict(json.loads(summary.to_json()))
    assert again == summary

    plain = summarise(
        replace(cfg, loop=LoopConfig(env="GridWorld")), [record(0, 41.5, math.nan)], set(), None
    )
    assert (plain.target, plain.target_score_mean, plain.rounds[0].target_score_mean) == (None,) * 3
    assert "true return 41.5 ± 2.6" in readme(plain)


def test_an_older_summary_still_loads_and_names_its_number_rightly():
    cfg = RunConfig(loop=LoopConfig(env="Hopper-backflip"))
    data = asdict(summarise(cfg, [record(0, 184.3, 0.2312)], set(), None))
    for key in ("target", "target_score_mean", "target_score_std"):
        del data[key]
    for row in data["rounds"]:
        del row["target_score_mean"], row["target_score_std"]
    data["measure"] = "target score (backward turns)"  # what it was: the per-step sum
    old = AgentSummary.from_dict(data)
    assert old.measure == "per-step score sum (rad/s)" and old.true_return_mean == 184.3
    assert (old.target, old.target_score_mean, old.rounds[0].target_score_mean) == (None,) * 3
    assert "per-step score sum (rad/s) 184 ± 3" in readme(old)


class Still:
    """A stand-in policy model: the zero action whatever it sees."""

    def __init__(self, shape):
        self.shape = shape

    def predict(self, obs, deterministic=True):
        return np.zeros(self.shape, dtype=np.float32), None


def test_evaluate_reports_a_target_envs_episode_score_beside_the_true_return():
    env = make_env("Hopper-backflip")
    summary = summarise(
        RunConfig(loop=LoopConfig(env="Hopper-backflip")), [record(0, 0, 0)], set(), None
    )
    summary = replace(summary, normalize_obs=False)
    agent = TrainedAgent(Still(env.action_space.shape), np.zeros(11), np.ones(11), summary, {})
    evaluation = agent.evaluate(episodes=2, seed=3)
    for i in range(2):  # by hand: the same episodes, the env's own total at the end
        env.reset(seed=3 + i)
        infos = [env.step(np.zeros(3))[4] for _ in range(1000)]
        assert evaluation.scores[i] == infos[-1][TARGET_TOTAL_KEY]
        assert evaluation.returns[i] == pytest.approx(sum(x[TRUE_REWARD_KEY] for x in infos))
    assert evaluation.target is TARGETS["hopper-backflip"]
    assert str(evaluation).startswith("backward turns per episode ")
    assert str(evaluation).endswith(" rad/s") and "(threshold 1) · per-step sum " in str(evaluation)


def test_a_target_rounds_record_holds_the_evaluations_episode_score():
    cfg = RunConfig(
        loop=LoopConfig(env="Walker2d-splits", eval_episodes=2, seed=5),
        ppo=PPOConfig(n_envs=1, n_steps=32, batch_size=16, n_epochs=1, tensorboard=False),
    )
    run = Run.create(cfg)
    row = train_frozen(run, 32)
    again = evaluate_episodes(run.make_env, run.agent.policy(deterministic=True), 2, eval_rng(5))
    assert row.target_score_mean == pytest.approx(again.scores.mean())
    assert row.target_score_std == pytest.approx(again.scores.std())
    assert row.true_return_mean == pytest.approx(again.returns.mean())
    assert row.target_score_mean != row.true_return_mean  # two different numbers
