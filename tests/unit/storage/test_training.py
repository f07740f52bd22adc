"""The learning curve's points (`storage.training`): written with a revision bump, read in
order or after a revision, and one per committed round from its stats."""

import math

from tests.unit.storage.conftest import prepared

from groupwise.storage import sessions as repo
from groupwise.storage.lifecycle import close_open_round, finish_training
from groupwise.storage.rounds import store_prepared_round
from groupwise.storage.training import add_point, list_points


def _add(s, sid, ppo_steps, true_return=None, **fields):
    values = {"round_index": 0, "pairs": 4, "reward_val_accuracy": 0.75, "pool_steps": 0}
    return add_point(s, sid, ppo_steps=ppo_steps, true_return=true_return, **values | fields)


def test_points_bump_the_revision_and_come_back_in_order(db, open_session):
    sid = open_session()
    with db.read() as s:
        before = repo.get_session(s, sid).revision
    with db.write() as s:
        first = _add(s, sid, 0, true_return=-3.5)
        second = _add(s, sid, 64, reward_val_accuracy=math.nan, pool_steps=32)
    assert (first.revision, second.revision) == (before + 1, before + 2)
    with db.read() as s:
        points = list_points(s, sid)
        assert repo.get_session(s, sid).revision == before + 2
        assert [p.ppo_steps for p in list_points(s, sid, after_revision=first.revision)] == [64]
    assert [(p.ppo_steps, p.true_return, p.reward_val_accuracy) for p in points] == [
        (0, -3.5, 0.75),
        (64, None, None),  # nan is stored as null
    ]
    assert points[1].pool_steps == 32
    assert points[0].at.tzinfo is not None


def test_a_committed_round_adds_its_point_its_pool_sampled_after_the_round_before(db, open_session):
    sid = open_session(rounds=3)
    stats = {"env_steps": 2048, "true_return_mean": 1.5, "pairs_total": 9}
    with db.write() as s:
        close_open_round(s, sid)
        assert finish_training(s, sid, 0, "x", {**stats, "reward_val_accuracy": None})
    with db.read() as s:
        (point,) = list_points(s, sid)
    assert (point.round, point.ppo_steps, point.true_return, point.pairs) == (0, 2048, 1.5, 9)
    assert (point.reward_val_accuracy, point.pool_steps) == (None, 0)
    with db.write() as s:  # round 1's pool came from the policy after round 0's 2,048 steps
        assert store_prepared_round(s, sid, 1, prepared())
        close_open_round(s, sid)
        assert finish_training(s, sid, 1, "y", {**stats, "env_steps": 4096})
    with db.read() as s:
        last = list_points(s, sid)[-1]
    assert (last.round, last.ppo_steps, last.pool_steps) == (1, 4096, 2048)
