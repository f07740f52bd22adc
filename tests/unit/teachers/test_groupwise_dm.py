import numpy as np

from groupwise.preferences.dataset import wrong_labels
from groupwise.preferences.pairs import cartesian_pairs, covering_pairs
from groupwise.query.groups import score_group_pairs, suggestion_order
from groupwise.query.strategies import GroupSuggestions, pool_candidates
from groupwise.teachers import Feedback
from groupwise.teachers.group_decision import Perception, SimulatedTeacher

NOISE_FREE = SimulatedTeacher(Perception(sigma=0.0))


def _returns(n, seed=1):
    return np.random.default_rng(seed).uniform(0.0, 30.0, size=n).tolist()


def test_at_most_n_judgements_small_disjoint_groups(make_pool):
    pool = make_pool(_returns(60))
    judgements = Feedback(GroupSuggestions(), SimulatedTeacher()).gather(
        pool, 20, np.random.default_rng(0)
    )
    assert 0 < len(judgements) <= 20
    for j in judgements:
        assert 1 <= len(j.left) <= 8 and 1 <= len(j.right) <= 8
        assert not set(j.left) & set(j.right)
        assert all(0 <= i < len(pool) for i in j.left + j.right)
    pairs = [p for j in judgements for p in covering_pairs(j, np.random.default_rng(0))]
    assert len(pairs) > len(judgements)  # groups give more than one pair per comparison


def test_asks_the_top_suggestions_in_order(make_pool):
    pool = make_pool(_returns(40))
    candidates = pool_candidates(pool)
    scores = score_group_pairs(pool.predicted_returns, pool.step_variance, candidates)
    rows = suggestion_order(scores, 5, refill=True)
    asked = [
        (set(candidates[a].members), set(candidates[b].members))
        for a, b in scores.pairs[rows].tolist()
    ]
    judgements = Feedback(GroupSuggestions(), NOISE_FREE).gather(pool, 5, np.random.default_rng(0))
    # every judgement is one of the top suggestions (outliers removed), in order
    assert judgements
    k = 0
    for j in judgements:
        while k < len(asked) and not (set(j.left) <= asked[k][0] and set(j.right) <= asked[k][1]):
            k += 1
        assert k < len(asked), f"{j} is not a top suggestion after the previous one"
        k += 1


def test_noise_free_dm_is_always_right(make_pool):
    pool = make_pool(_returns(80, seed=2))
    judgements = Feedback(GroupSuggestions(), NOISE_FREE).gather(pool, 40, np.random.default_rng(3))
    assert judgements
    true = pool.true_returns
    for derive in (covering_pairs, cartesian_pairs):
        pairs = [p for j in judgements for p in derive(j, np.random.default_rng(0))]
        a, b = np.array([p.a for p in pairs]), np.array([p.b for p in pairs])
        labels = np.array([p.label for p in pairs])
        assert not wrong_labels(true[a], true[b], labels).any()


def test_same_seed_same_judgements(make_pool):
    pool = make_pool(_returns(50))
    dm = Feedback(GroupSuggestions(), SimulatedTeacher())
    first = dm.gather(pool, 15, np.random.default_rng(7))
    assert first == dm.gather(pool, 15, np.random.default_rng(7))


def test_works_without_step_variance(make_pool):
    pool = make_pool(_returns(40), step_variance=False)
    assert pool.step_variance is None
    judgements = Feedback(GroupSuggestions(), NOISE_FREE).gather(pool, 10, np.random.default_rng(0))
    assert 0 < len(judgements) <= 10


def test_refill_asks_beyond_one_suggestion_list(make_pool):
    pool = make_pool(_returns(40))
    one_list = Feedback(GroupSuggestions(refill=False), NOISE_FREE).gather(
        pool, 200, np.random.default_rng(0)
    )
    refilled = Feedback(GroupSuggestions(), NOISE_FREE).gather(pool, 200, np.random.default_rng(0))
    # each candidate is in at most 2 suggestions of one list: at most G suggestions
    assert len(one_list) <= len(pool_candidates(pool))
    assert len(refilled) > len(one_list)


def test_tiny_pools(make_pool):
    assert (
        Feedback(GroupSuggestions(), SimulatedTeacher()).gather(
            make_pool([1.0]), 5, np.random.default_rng(0)
        )
        == []
    )
    assert (
        Feedback(GroupSuggestions(), SimulatedTeacher()).gather(
            make_pool([1.0, 2.0]), 5, np.random.default_rng(0)
        )
        == []
    )
    assert (
        Feedback(GroupSuggestions(), SimulatedTeacher()).gather(
            make_pool(_returns(10)), 0, np.random.default_rng(0)
        )
        == []
    )
