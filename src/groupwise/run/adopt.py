"""The policy takes over a pool variant's push when the teacher prefers its behaviours (issue 20).

A round's pool may come partly from biased variants of the policy (`LoopConfig.pool_variants`:
its actions shifted by a fixed offset each, `rl.policy.biased_variants`), so that the
teacher sees behaviours the policy itself rarely reaches. The teacher may prefer one of
them, and the reward model learn it, but PPO learns from the policy's own episodes and need
not find its way there: in a walker run the greedy episodes of one variant held the split
6.5 s (1,383 of the step score) while the policy's held 0.09 s (733), the teacher
preferred every full split it was shown, and PPO never split in two more rounds
(docs/results/case-studies/adopt). With `LoopConfig.adopt_variants`, after the round's
feedback and before its PPO:

    k = preferred_variant(fragment_sources(pool), pairs)   # the round's pairs decide
    agent.shift_actions(variants[k - 1].offset)            # the policy moves there

`preferred_variant` counts each variant's preference pairs of the round against the
policy's own behaviours (won 1, equal ½, lost 0); the variant with the largest share of
wins, above ½ over at least `MIN_PAIRS` such pairs, is adopted (ties: the more pairs, then
the lower k); none otherwise. The teacher is asked nothing more, and the reward model is
not touched: PPO then trains the moved policy on it.
"""

from collections.abc import Sequence

from groupwise.pool.behaviours import BehaviourPool
from groupwise.preferences.pairs import Pair
from groupwise.rl.policy import BiasedPolicy
from groupwise.run.run import Run

MIN_PAIRS = 4
"""Pairs against the policy's behaviours a variant needs before it can be adopted: with the
teacher wrong on about 12 % of pairs, four straight wins are unlikely by chance (0.5 % if
the variant were no better, about half a percent a round over 8 variants each)."""


def fragment_sources(pool: BehaviourPool) -> list[int]:
    """Each pool behaviour's source: 0 the round's policy, k its k-th variant
    (`Trajectory.source` of the episode it was cut from; 0 when the pool has no episodes)."""
    source = {episode.episode: episode.source for episode in pool.episodes}
    return [source.get(fragment.episode, 0) for fragment in pool.fragments]


def preferred_variant(
    sources: Sequence[int], pairs: Sequence[Pair], min_pairs: int = MIN_PAIRS
) -> int | None:
    """The variant (k >= 1) the pairs prefer to the policy (module docstring), or None.

    `sources` gives each pool index's source, `pairs` index the pool.
    """
    won: dict[int, float] = {}
    seen: dict[int, int] = {}
    for pair in pairs:
        a, b = sources[pair.a], sources[pair.b]
        if (a == 0) == (b == 0):  # not a variant against the policy
            continue
        variant, wins = (a, pair.label) if a != 0 else (b, 1.0 - pair.label)
        won[variant] = won.get(variant, 0.0) + wins
        seen[variant] = seen.get(variant, 0) + 1
    ranked = sorted(
        (won[k] / seen[k], seen[k], -k) for k in seen if seen[k] >= min_pairs and won[k] > 0
    )
    if not ranked or ranked[-1][0] <= 0.5:
        return None
    return -ranked[-1][2]


def adopt_variant(
    run: Run, pool: BehaviourPool, variants: Sequence[BiasedPolicy], pairs: Sequence[Pair]
) -> int:
    """Shift the run's policy by the offset of the variant `pairs` prefer (`preferred_variant`
    over `pool`'s sources); the variant's number, 0 when none is adopted (no variants, no
    Box offsets, or none preferred).
    """
    offsets = [v.offset for v in variants]
    if not offsets or any(offset is None for offset in offsets):
        return 0
    k = preferred_variant(fragment_sources(pool), pairs)
    if k is None:
        return 0
    offset = offsets[k - 1]
    assert offset is not None
    run.ppo.shift_actions(offset)
    return k
