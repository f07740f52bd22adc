import dataclasses
from collections import Counter

import numpy as np
import pytest

from groupwise.behaviour import TreeConfig
from groupwise.config import RunConfig, TeacherConfig
from groupwise.preferences.dataset import wrong_labels
from groupwise.preferences.judgement import LEFT_BETTER
from groupwise.preferences.pairs import covering_pairs
from groupwise.query.interactive import chain_pairs, evenly_spaced
from groupwise.query.strategies import InteractiveWalk, pool_candidates
from groupwise.teachers import DECISION_MAKERS, Feedback
from groupwise.teachers.calibration import calibrated_noise_sd
from groupwise.teachers.group_decision import Perception, SimulatedTeacher

LINEAR = TreeConfig(bands="linear")
"""The cut the hand-built cluster pool was laid out for."""
NOISE_FREE = SimulatedTeacher(Perception(sigma=0.0))


def test_chain_pairs_by_hand():
    groups = [(0, 1), (0, 1, 2, 3), (2, 3), (4, 5), (6, 7)]
    means = [10.0, 8.0, 6.0, 4.0, 2.0]
    # G0 skips G1 (shares 0 and 1) and takes G2; G1 then takes G3 (G2 overlaps it);
    # G2's behaviours are used twice by now, so it starts nothing; G3 takes G4.
    assert chain_pairs(groups, means) == [(0, 2), (1, 3), (3, 4)]
    # ranking, not list order, decides
    assert chain_pairs(groups[::-1], means[::-1]) == [(4, 2), (3, 1), (1, 0)]


def test_chain_pairs_each_behaviour_at_most_twice_and_disjoint():
    rng = np.random.default_rng(0)
    groups = [tuple(rng.choice(30, size=rng.integers(2, 9), replace=False)) for _ in range(40)]
    means = rng.normal(size=40)
    pairs = chain_pairs(groups, means)
    uses = Counter(i for g, h in pairs for i in (*groups[g], *groups[h]))
    assert max(uses.values()) <= 2
    for g, h in pairs:
        assert not set(groups[g]) & set(groups[h])
        assert means[g] >= means[h]  # best to worst: the left group ranks higher
    lefts = [means[g] for g, _ in pairs]
    assert lefts == sorted(lefts, reverse=True)


def test_chain_pairs_with_a_min_gap_skips_partners_too_close_to_call():
    groups = [(0,), (1,), (2,), (3,), (4,)]
    means = [10.0, 9.0, 6.0, 5.5, 1.0]
    assert chain_pairs(groups, means) == [(0, 1), (1, 2), (2, 3), (3, 4)]
    # a gap of 3: 10 passes over 9 (1 lower) to 6; 9 takes 6 (exactly 3 lower), now used
    # twice, so 6 starts nothing; 5.5 takes 1
    assert chain_pairs(groups, means, min_gap=3.0) == [(0, 2), (1, 2), (3, 4)]
    # each once: 9 passes over the used 6 to 5.5; nothing is left for 1
    assert chain_pairs(groups, means, max_uses=1, min_gap=3.0) == [(0, 2), (1, 3)]
    assert chain_pairs(groups, means, min_gap=20.0) == []
    with pytest.raises(ValueError, match="min gap"):
        chain_pairs(groups, means, min_gap=-1.0)


def test_evenly_spaced():
    assert evenly_spaced(5, 10) == [0, 1, 2, 3, 4]
    assert evenly_spaced(9, 3) == [0, 4, 8]
    assert evenly_spaced(10, 4) == [0, 3, 6, 9]
    assert evenly_spaced(5, 1) == [0]
    assert evenly_spaced(5, 0) == []


# four clusters of sizes 2, 6, 3, 4 with mean returns 30, 20, 25, 5 (every member of a
# cluster has its cluster's return). By mean: c0 (30) > c2 (25) > c1 (20) > c3 (5); by sum
# it would be c1 (120) > c2 (75) > c0 (60) > c3 (20).
SIZES = [2, 6, 3, 4]
MEANS = [30.0, 20.0, 25.0, 5.0]
CLUSTERS = [c for c, size in enumerate(SIZES) for _ in range(size)]


def _cluster_pool(make_pool):
    return make_pool([MEANS[c] for c in CLUSTERS], clusters=CLUSTERS)


def _members(c):
    return {i for i, ci in enumerate(CLUSTERS) if ci == c}


def test_pairs_neighbours_by_mean_return_best_to_worst(make_pool):
    pool = _cluster_pool(make_pool)
    # the tree finds exactly the four clusters as candidates
    assert sorted(map(set, (c.members for c in pool_candidates(pool, LINEAR))), key=min) == [
        _members(c) for c in (0, 1, 2, 3)
    ]
    judgements = Feedback(InteractiveWalk(tree=LINEAR), NOISE_FREE).gather(
        pool, 10, np.random.default_rng(0)
    )
    asked = [(set(j.left), set(j.right)) for j in judgements]
    assert asked == [
        (_members(0), _members(2)),
        (_members(2), _members(1)),
        (_members(1), _members(3)),
    ]
    assert all(j.label == LEFT_BETTER and j.edits == 0 for j in judgements)


def test_distinct_walk_compares_only_groups_far_enough_apart(make_pool):
    pool = _cluster_pool(make_pool)
    # means 30 > 25 > 20 > 5: with a gap of 8, c0 passes over c2 (5 lower) to c1 (10 lower);
    # c2 passes over c1 (5 lower) to c3; c1 (used once) takes c3 (used once) as well
    judgements = Feedback(InteractiveWalk(tree=LINEAR, min_gap=8.0), NOISE_FREE).gather(
        pool, 10, np.random.default_rng(0)
    )
    assert [(set(j.left), set(j.right)) for j in judgements] == [
        (_members(0), _members(1)),
        (_members(2), _members(3)),
        (_members(1), _members(3)),
    ]


def test_more_pairs_than_queries_keep_the_ends(make_pool):
    pool = _cluster_pool(make_pool)
    judgements = Feedback(InteractiveWalk(tree=LINEAR), NOISE_FREE).gather(
        pool, 2, np.random.default_rng(0)
    )
    assert [(set(j.left), set(j.right)) for j in judgements] == [
        (_members(0), _members(2)),
        (_members(1), _members(3)),
    ]


def _random_pool(make_pool, n=80, seed=4):
    return make_pool(np.random.default_rng(seed).uniform(0, 30, size=n).tolist(), seed=seed)


def test_random_pool_uses_each_behaviour_at_most_twice(make_pool):
    pool = _random_pool(make_pool)
    judgements = Feedback(InteractiveWalk(tree=LINEAR), SimulatedTeacher()).gather(
        pool, 40, np.random.default_rng(0)
    )
    assert 0 < len(judgements) <= 40
    uses = Counter(i for j in judgements for i in j.left + j.right)
    assert max(uses.values()) <= 2
    assert all(len(j.left) <= 8 and len(j.right) <= 8 for j in judgements)


def test_noise_free_dm_is_always_right_and_seeded(make_pool):
    pool = _random_pool(make_pool, seed=5)
    dm = Feedback(InteractiveWalk(tree=LINEAR), NOISE_FREE)
    judgements = dm.gather(pool, 40, np.random.default_rng(1))
    pairs = [p for j in judgements for p in covering_pairs(j, np.random.default_rng(0))]
    true = pool.true_returns
    a, b = np.array([p.a for p in pairs]), np.array([p.b for p in pairs])
    assert not wrong_labels(true[a], true[b], np.array([p.label for p in pairs])).any()
    noisy = Feedback(InteractiveWalk(tree=LINEAR), SimulatedTeacher())
    assert noisy.gather(pool, 40, np.random.default_rng(9)) == noisy.gather(
        pool, 40, np.random.default_rng(9)
    )


def test_reference_walk_ranks_by_sum_over_all_groups_in_two_passes(make_pool):
    pool = _random_pool(make_pool, n=120, seed=6)
    # the reference code's tree: counts, without the size caps (issue 22) that keep its
    # level-1 nodes within 8 behaviours
    reference = InteractiveWalk(
        tree=TreeConfig(balance=None),
        rank="sum",
        min_group=1,
        max_group=10**6,
        padding=True,
        passes=2,
    )
    candidates = reference.candidates(pool)
    assert max(len(c.members) for c in candidates) > 8  # no 8-behaviour limit
    assert min(len(c.members) for c in candidates) == 1  # padding over single leaves
    assert len({frozenset(c.members) for c in candidates}) == len(candidates)
    one_pass = dataclasses.replace(reference, passes=1).propose(pool, 10**6, None)
    two = reference.propose(pool, 10**6, None)
    assert two[: len(one_pass)] == one_pass and len(two) >= len(one_pass)
    sums = {frozenset(c.members): pool.true_returns[list(c.members)].sum() for c in candidates}
    assert all(sums[frozenset(q.left)] >= sums[frozenset(q.right)] for q in two)


@pytest.mark.parametrize("z", [0.5, 1.0])
def test_clear_walk_uses_its_budget_and_never_pairs_groups_closer_than_its_threshold(make_pool, z):
    pool = _random_pool(make_pool, n=120, seed=7)
    noise_sd = 30 * 0.25  # L·σ of the fixture's 30-step fragments
    walk = InteractiveWalk(clear=z, noise_sd=noise_sd)
    budget = 40
    queries = walk.propose(pool, budget, None)
    true = pool.true_returns
    found = len(queries)
    # the whole budget, or every clear comparison there is (then it says why: none left)
    everything = walk.propose(pool, 10**6, None)
    assert found == budget or found == len(everything)
    for q in queries:
        left, right = true[list(q.left)], true[list(q.right)]
        gap = z * np.sqrt((left.std() ** 2 + right.std() ** 2) / 2 + noise_sd**2)
        assert left.mean() - right.mean() >= gap - 1e-9
    # the spec's walk leaves most of the same budget unasked on the same pool
    assert len(InteractiveWalk().propose(pool, budget, None)) < found


def test_clear_walk_with_nothing_clear_walks_as_the_papers_text_does(make_pool):
    # a case-study target's early pool: most behaviours score exactly 0
    returns = np.zeros(60)
    returns[:3] = [0.02, 0.01, 0.005]
    pool = make_pool(returns.tolist(), seed=3)
    clear = InteractiveWalk(clear=1.0, noise_sd=30 * 0.25)  # SPEC σ: nothing is clear
    mean = InteractiveWalk()
    queries = clear.propose(pool, 40, None)
    assert queries and queries == mean.propose(pool, 40, None)


def test_clear_walk_of_a_calibrated_teacher_sees_gaps_on_the_pools_scale(make_pool):
    # returns of a hundredth of SPEC §7's noise: a calibrated teacher still tells them apart
    pool = _random_pool(make_pool, n=120, seed=7)
    small = make_pool((pool.true_returns / 100).tolist(), seed=7)
    noise = calibrated_noise_sd(small.true_returns, 0.12)
    walk = InteractiveWalk(
        clear=1.0, noise_sd=30 * 0.25, perceived_noise=lambda r: calibrated_noise_sd(r, 0.12)
    )
    queries = walk.propose(small, 40, None)
    assert len(queries) == 40
    true = small.true_returns
    for q in queries:
        left, right = true[list(q.left)], true[list(q.right)]
        assert (
            left.mean() - right.mean()
            >= np.sqrt((left.std() ** 2 + right.std() ** 2) / 2 + noise**2) - 1e-12
        )
    # the registered DM reads the noise from a calibrated teacher's config
    cfg = RunConfig(teacher=TeacherConfig(label_error=0.12))
    assert DECISION_MAKERS["interactive-clear"](cfg).queries.propose(small, 40, None) == queries
