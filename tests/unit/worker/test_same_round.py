"""An app round and a headless round are one round: the same seed and the same judgements
give the same pool, queries, pairs, dataset and reward model, bit for bit.

The app's side runs as a user's page and the worker do: judgements (one undone) posted to
the real HTTP routes on a real SQLite database, the worker's jobs picked up from it
(`Worker.run_next`: prepare, train). The headless side is `begin_round` → the same
judgements → `end_round` on a `Run` of the session's own config. In continuous training
(issue 39) the worker trains the open round slice by slice and cuts the next pool from the
run's latest rollouts; the headless side drives `run.continuous.ContinuousRound` alike.
"""

import json
import uuid
from pathlib import Path

import numpy as np
import torch
from sqlalchemy import select
from tests.unit.server.conftest import (
    TINY,
    context_of,
    new_session,
    post_judgement,
    run_worker_once,
)

from groupwise.config import RunConfig
from groupwise.episodes.ids import behaviour_index
from groupwise.pool.files import load_fragments, load_pool
from groupwise.pool.recent import fresh_sources, kept_tag
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.preferences.judgement import LEFT_BETTER, RIGHT_BETTER, Judgement
from groupwise.run.continuous import ContinuousRound, cut_next
from groupwise.run.progress import RunCallback
from groupwise.run.round import begin_round, end_round, finish_round
from groupwise.run.run import CONFIG_FILE, Run
from groupwise.run.streams import round_streams
from groupwise.storage.models import PairQueueRow, RoundRow, SuggestionRow
from groupwise.storage.sessions import round_directory
from groupwise.storage.settings import SessionSettings
from groupwise.worker.job import offered_queries, session_strategy
from groupwise.worker.jobs import OPENING_FILE
from groupwise.worker.process import Worker
from groupwise.worker.publishing import sampled_at

# round → (left, right, label, undone) in the order given; the undone one keeps its key
ANSWERS = {
    0: [(("b0", "b1"), ("b2",), "left", False), (("b5",), ("b3", "b4", "b6"), "right", False)],
    1: [
        (("b2", "b7"), ("b1",), "right", False),
        (("b9",), ("b8",), "left", True),
        (("b3", "b4", "b10", "b13"), ("b11", "b12", "b14"), "left", False),
    ],
}
LABELS = {"left": LEFT_BETTER, "right": RIGHT_BETTER}


def _answer(client, sid: str, round_index: int) -> None:
    for left, right, label, undone in ANSWERS[round_index]:
        body = {
            "client_id": str(uuid.uuid4()),
            "round": round_index,
            "left": list(left),
            "right": list(right),
            "label": label,
            "source": "explored",
        }
        stored = client.post(f"/api/sessions/{sid}/judgements", json=body)
        assert stored.status_code == 201, stored.text
        if undone:
            gone = client.delete(f"/api/sessions/{sid}/judgements/{stored.json()['id']}")
            assert gone.status_code == 200, gone.text
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"


def _kept(round_index: int) -> tuple[list[Judgement], list[int]]:
    """The judgements the app trains on and their keys (places in the round)."""
    kept = [
        (
            key,
            Judgement(
                tuple(map(behaviour_index, left)), tuple(map(behaviour_index, right)), LABELS[label]
            ),
        )
        for key, (left, right, label, undone) in enumerate(ANSWERS[round_index])
        if not undone
    ]
    return [j for _, j in kept], [k for k, _ in kept]


def _state(checkpoint: Path) -> tuple[PreferenceDataset, dict[str, torch.Tensor]]:
    """The checkpoint's dataset and the reward ensemble's parameters (with its normaliser
    and L2 weight)."""
    saved = torch.load(checkpoint / "reward.pt", weights_only=True)
    params = {**saved["state_dict"], "l2_weight": torch.as_tensor(saved["l2_weight"])}
    return PreferenceDataset.load(checkpoint / "dataset.npz"), params


def test_an_app_round_and_a_headless_round_are_the_same_round(client, tmp_path):
    chosen = {"seed": 7, "training": "rounds"}  # PPO after each round, as the headless loop
    sid = new_session(client, **chosen)["id"]
    data = context_of(client).data_dir
    app_dir = data / "sessions" / sid
    settings = SessionSettings.model_validate({**TINY, **chosen}).for_env("GridWorld")
    for r in (0, 1):
        run_worker_once(client)  # prepare round r
        _answer(client, sid, r)
        run_worker_once(client)  # train after round r
    cfg = RunConfig.load(app_dir / CONFIG_FILE)
    assert cfg == settings.run_config("GridWorld")

    with Run.create(cfg, tmp_path / "headless") as run:
        for r in (0, 1):
            offer = begin_round(
                run,
                session_strategy(cfg, "groupwise"),
                settings.comparisons_per_round,
                n_queries=offered_queries(settings),
            )
            # the same pool …
            _same_pool(load_fragments(data / round_directory(sid, r)), offer.pool)
            # … and the same queries, stored as the page's suggestions in their order
            context = context_of(client)
            assert _suggestions(context, sid, r) == [(q.left, q.right) for q in offer.queries]
            with context.db.read() as s:
                assert not s.scalars(
                    select(PairQueueRow)
                    .join(RoundRow, RoundRow.id == PairQueueRow.round_id)
                    .where(RoundRow.session_id == sid, RoundRow.index == r)
                ).first()
            assert offer.queries, "the group strategy proposed nothing"

            judgements, keys = _kept(r)
            end_round(run, offer, judgements, settings.ppo_steps_per_round, keys=keys)

            app_data, app_reward = _state(app_dir / "checkpoints" / f"round-{r:04d}")
            our_data, our_reward = _state(tmp_path / "headless" / "checkpoints" / f"round-{r:04d}")
            assert len(app_data) == len(our_data) > 0
            for name in ("obs", "acts", "true_returns", "pairs", "labels", "rounds"):
                assert np.array_equal(getattr(app_data, name), getattr(our_data, name)), name
            assert app_reward.keys() == our_reward.keys()
            for name, tensor in app_reward.items():
                assert torch.equal(tensor, our_reward[name]), name
    # the pairs stored with each judgement are the pairs trained on
    listed = client.get(f"/api/sessions/{sid}/judgements").json()
    assert sum(len(j["pairs"]) for j in listed) == len(our_data)


def _suggestions(context, sid: str, round_index: int) -> list[tuple[tuple[int, ...], ...]]:
    """Round `round_index`'s stored suggestions, in their order, as (left, right) indices."""
    with context.db.read() as s:
        round_id = s.scalar(
            select(RoundRow.id).where(RoundRow.session_id == sid, RoundRow.index == round_index)
        )
        stored = s.scalars(
            select(SuggestionRow)
            .where(SuggestionRow.round_id == round_id)
            .order_by(SuggestionRow.rank)
        ).all()
    return [
        (tuple(map(behaviour_index, q.left)), tuple(map(behaviour_index, q.right))) for q in stored
    ]


def _same_pool(published, pool) -> None:
    assert len(published) == len(pool)
    for ours, theirs in zip(pool.fragments, published, strict=True):
        assert np.array_equal(ours.obs, theirs.obs)
        assert np.array_equal(ours.acts, theirs.acts)


def test_a_continuous_app_round_and_a_headless_continuous_round_are_the_same_round(
    client, tmp_path
):
    """The continuous path (issue 39): the worker trains the open round slice by slice and,
    when the round ends, cuts the next pool from its run's latest rollouts; the headless
    continuous round (`run.continuous`: `ContinuousRound`, `pool.recent.fresh_sources`) does the
    same with the same judgements and rollouts, and gets the same next pool, bit for bit."""
    chosen = {"seed": 11, "training": "continuous"}
    slices = 12  # 384 PPO steps: the next pool's 32 windows all from the recorded rollouts
    sid = new_session(client, **chosen)["id"]
    context = context_of(client)
    app_dir = context.data_dir / "sessions" / sid
    settings = SessionSettings.model_validate({**TINY, **chosen}).for_env("GridWorld")
    run_worker_once(client)  # prepare round 0
    for left, right, label, _ in ANSWERS[0]:
        body = {"client_id": str(uuid.uuid4()), "round": 0, "left": list(left),
                "right": list(right), "label": label, "source": "explored"}  # fmt: skip
        assert client.post(f"/api/sessions/{sid}/judgements", json=body).status_code == 201
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    for _ in range(slices):
        assert worker.train_continuous()
    assert client.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
    assert worker.run_next()  # round 1 cut from round 0's rollouts and opened; 0 committed
    worker.continuous.close()
    assert client.get(f"/api/sessions/{sid}").json()["round"] == 1
    cfg = RunConfig.load(app_dir / CONFIG_FILE)
    assert cfg == settings.run_config("GridWorld")

    strategy = session_strategy(cfg, "groupwise")
    queries = offered_queries(settings)
    budget = settings.comparisons_per_round
    with Run.create(cfg, tmp_path / "headless") as run:
        offer = begin_round(
            run, strategy, budget, n_queries=queries, sources=fresh_sources(cfg.loop)
        )
        _same_pool(load_fragments(context.data_dir / round_directory(sid, 0)), offer.pool)
        judgements, keys = _kept(0)
        continuous = ContinuousRound(run, offer, round_streams(cfg.loop.seed, 0), 0.0)
        continuous.update(list(zip(keys, judgements, strict=True)), 0.0, final=True)
        for _ in range(slices):
            continuous.learn(run.ppo.rollout_steps)
        finish_round(
            run, offer, judgements, continuous.report, continuous.timer, RunCallback(), asked=None
        )
        following = cut_next(run, strategy, budget, 1, queries, judged=offer.pool).offer
        assert run.agent.num_timesteps == slices * run.ppo.rollout_steps
    # the same round 0: dataset and reward model …
    app_data, app_reward = _state(app_dir / "checkpoints" / "round-0000")
    our_data, our_reward = _state(tmp_path / "headless" / "checkpoints" / "round-0000")
    for name in ("obs", "acts", "true_returns", "pairs", "labels", "rounds"):
        assert np.array_equal(getattr(app_data, name), getattr(our_data, name)), name
    for name, tensor in app_reward.items():
        assert torch.equal(tensor, our_reward[name]), name
    # … and the same next pool, of the rollouts PPO played, and the same suggestions
    published = load_fragments(context.data_dir / round_directory(sid, 1))
    _same_pool(published, following.pool)
    recorded = {e.reset_seed for e in following.pool.episodes if e.source == 0}
    sources = load_pool(context.data_dir / round_directory(sid, 1), 1).sources
    assert np.array_equal(sources, following.pool.sources)
    # the windows come from the rollouts PPO played and from a share of the policy round 0
    # was cut from (`run.kept_policy`), nothing else
    kept = kept_tag(cfg.loop)
    assert set(sources.tolist()) <= {0, kept} and np.any(sources == kept)
    fresh = {f.reset_seed for f, source in zip(published, sources, strict=True) if source == 0}
    assert fresh <= recorded
    # the kept share is as old as round 0's policy; the pool's place on the curve is not
    directory = context.data_dir / round_directory(sid, 1)
    ages = np.array(json.loads((directory / "pool.json").read_text())["metadata"]["ages"])
    now = slices * 32  # TINY's rollouts: 1 env × 32 steps
    assert (ages[sources == kept] == now).all()
    assert sampled_at(directory) == now - ages[sources != kept].max(initial=0)
    assert _suggestions(context, sid, 1) == [(q.left, q.right) for q in following.queries]


def test_a_round_ended_by_its_budget_opens_the_pool_cut_during_its_last_comparison(
    client, tmp_path
):
    """Issue 39, End round ≤ 2 s: once all but the last of the round's comparisons are in,
    the worker cuts and publishes the next pool and PPO waits; the last comparison ends the
    round at its budget and the job opens that pool at once, the same pool and suggestions
    as the headless continuous round cuts at that point (`run.continuous.cut_next`)."""
    chosen = {"seed": 5, "training": "continuous", "comparisons_per_round": 3}
    slices = 6
    sid = new_session(client, **chosen)["id"]
    context = context_of(client)
    settings = SessionSettings.model_validate({**TINY, **chosen}).for_env("GridWorld")
    run_worker_once(client)  # prepare round 0
    answers = [(["b0", "b1"], ["b2"]), (["b5"], ["b3", "b4"]), (["b7"], ["b6"])]
    post_judgement(client, sid, *answers[0])
    worker = Worker(context.db, context.data_dir, poll_s=0.1)
    for _ in range(slices):
        assert worker.train_continuous()
    post_judgement(client, sid, *answers[1])  # one short of the budget: the next pool is cut
    assert not worker.train_continuous()  # … and PPO waits for the last comparison
    assert not worker.train_continuous()
    staged = load_fragments(context.data_dir / round_directory(sid, 1))
    post_judgement(client, sid, *answers[2])
    assert client.get(f"/api/sessions/{sid}").json()["phase"] == "training"  # its budget
    assert worker.run_next()  # round 1 opened with the staged pool, round 0 committed
    worker.continuous.close()
    assert client.get(f"/api/sessions/{sid}").json()["round"] == 1
    opening = json.loads((context.data_dir / round_directory(sid, 1) / OPENING_FILE).read_text())
    assert set(opening["staged_s"]) == {"sample", "cut", "publish"}
    assert "sample" not in opening["parts_s"] and "refit" not in opening["parts_s"]
    cfg = RunConfig.load(context.data_dir / "sessions" / sid / CONFIG_FILE)

    judgements = [
        Judgement(
            tuple(map(behaviour_index, left)), tuple(map(behaviour_index, right)), LEFT_BETTER
        )
        for left, right in answers  # post_judgement's "left"
    ]
    budget = settings.comparisons_per_round
    with Run.create(cfg, tmp_path / "headless") as run:
        offer = begin_round(
            run,
            session_strategy(cfg, "groupwise"),
            budget,
            n_queries=offered_queries(settings),
            sources=fresh_sources(cfg.loop),
        )
        continuous = ContinuousRound(run, offer, round_streams(cfg.loop.seed, 0), 0.0)
        continuous.update(list(enumerate(judgements[:1])), 0.0)
        for _ in range(slices):
            continuous.learn(run.ppo.rollout_steps)
        continuous.update(list(enumerate(judgements[:2])), 1.0)  # no refit due
        following = cut_next(
            run,
            session_strategy(cfg, "groupwise"),
            budget,
            1,
            offered_queries(settings),
            judged=offer.pool,
        )
        continuous.update(list(enumerate(judgements)), 2.0, final=True)
        assert run.agent.num_timesteps == slices * run.ppo.rollout_steps
    _same_pool(staged, following.offer.pool)
    _same_pool(load_fragments(context.data_dir / round_directory(sid, 1)), following.offer.pool)
    assert _suggestions(context, sid, 1) == [(q.left, q.right) for q in following.offer.queries]
