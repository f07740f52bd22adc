"""The policy takes over a pool variant's push when the teacher prefers its behaviours (issue 20).

A round's pool may come partly from biased variants of the policy (`LoopConfig.pool_variants`:
its actions shifted by a fixed offset each, `rl.policy.biased_variants`), so that the
teacher sees behaviours the policy itself rarely reaches. The teacher may prefer one of
them, and the reward model learn it, but PPO learns from the policy's own episodes and need
not find its way there: in a walker run the greedy episodes of one variant held the split
6.5 s (1,383 of the step score) while the policy's held 0.09 s (733), after the teacher had
preferred each of the 16 full splits it was shown (docs/results/case-studies/walker,
`variant_episodes.py`). With `LoopConfig.adopt_variants`, after the round's feedback and
before its PPO:

    k = preferred_variant(fragment_sources(pool), pairs)   # the round's pairs decide
    agent.shift_actions(variants[k - 1].offset)            # the policy moves there

`preferred_variant` counts each variant's preference pairs of the round against the
policy's own behaviours (won 1, equal ½, lost 0) and adopts the one whose wins are
significant: a one-sided binomial test against ½ at 5 % over all K variants together
(Bonferroni: `ALPHA` / K each; with 8 variants 8 wins of 8 pass, 7 of 8 do not). A first
rule, any variant above ½ over 4 or more pairs, adopted a variant in most rounds of most
walker runs, a random walk of pushes that taught the splits in none of 5 seeds
(docs/results/case-studies/walker/adopt-any). The teacher is asked nothing more, and the
reward model is not touched: PPO then trains the moved policy on it.
"""

import math
from collections.abc import Sequence

from scipy.stats import binomtest

from groupwise.pool.behaviours import BehaviourPool
from groupwise.preferences.pairs import Pair
from groupwise.rl.policy import BiasedPolicy
from groupwise.run.run import Run

ALPHA = 0.05
"""The chance, over all of a round's variants together, of adopting one that the policy's
behaviours would beat as often as not: each variant's wins are tested at `ALPHA` / K."""


def fragment_sources(pool: BehaviourPool) -> list[int]:
    """Each pool behaviour's source: 0 the round's policy, k its k-th variant
    (`Trajectory.source` of the episode it was cut from; 0 when the pool has no episodes)."""
    source = {episode.episode: episode.source for episode in pool.episodes}
    return [source.get(fragment.episode, 0) for fragment in pool.fragments]


def preferred_variant(
    sources: Sequence[int], pairs: Sequence[Pair], alpha: float = ALPHA
) -> int | None:
    """The variant (k >= 1) the pairs prefer to the policy (module docstring), or None.

    `sources` gives each pool index's source (0 the policy, 1 … K its variants), `pairs`
    index the pool. A variant's wins are its pairs won against the policy's behaviours (an
    equal answer half a win, rounded down over the variant's pairs); it is preferred when a
    one-sided binomial test of them against ½ gives p < `alpha` / K, and among several the
    one of the smallest p (then the lower k).
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
    variants = max(sources, default=0)
    tested = sorted(
        (binomtest(math.floor(won[k]), seen[k], 0.5, alternative="greater").pvalue, k) for k in seen
    )
    if not tested or tested[0][0] >= alpha / variants:
        return None
    return tested[0][1]


def adopt_variant(
    run: Run, pool: BehaviourPool, variants: Sequence[BiasedPolicy], pairs: Sequence[Pair]
) -> int:
    """Shift the run's policy by the offset of the variant `pairs` prefer (`preferred_variant`
    over `pool`'s sources); the variant's number, 0 when none is adopted (none preferred, or
    the preferred one pushes nothing: a Discrete variant, or `pool_variants_greedy`'s first).
    """
    k = preferred_variant(fragment_sources(pool), pairs) if variants else None
    offset = None if k is None else variants[k - 1].offset
    if k is None or offset is None or not offset.any():  # nothing to move by
        return 0
    run.ppo.shift_actions(offset)
    return k
