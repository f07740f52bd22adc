"""Which policy a round's PPO trains on from: the one the teacher prefers so far (issue 20).

A run's rounds train one policy on a reward model that is refitted every round, and a
refit can lead PPO away from what the teacher wanted: case-study runs that had learned
their target lost it a round later (a walker held a split in 3 of 5 episodes after round 2
and in none after round 3, its return falling from 851 to 385; docs/case-studies.md, "Kept
once learned"). The take-away choice (`groupwise.run.takeaway`) hands over the best round
at the end, but the rounds after it have trained on from the worse policy. With
`TrainingConfig.continue_from` "preferred" the run keeps the teacher's preferred policy
as it goes:

    start = keep_preferred(run, teacher)   # before round r: the round whose policy trains on
    run_round(run, ...)                    # samples its pool from that policy and trains it

Before round r >= 2 the teacher compares `TrainingConfig.continue_episodes` greedy
episodes of round r − 1's policy with as many of the policy round r − 1 began from (its
`RoundRecord.continued_from`, the preferred one so far), from the same reset seeds, as
the take-away choice compares rounds (`takeaway.choose_round`, the later on a tie). When it
prefers the earlier policy the agent goes back to that round's checkpoint (`PPOAgent.revert`:
policy, optimiser and observation statistics; the PPO step count goes on). The reward model
is never reverted: it keeps every judgement, including those about the policy set aside.
The teacher's verdicts are on whole episodes: they are not preference pairs and do not
count as the run's comparisons. Their randomness is the round's own (`streams.keep_streams`),
so a resumed run makes the same choice.
"""

import logging

from groupwise.oracles.base import Teacher
from groupwise.run.checkpoint import checkpoint_dir
from groupwise.run.final import round_episodes
from groupwise.run.progress import RunCallback
from groupwise.run.run import Run
from groupwise.run.streams import keep_streams
from groupwise.run.takeaway import choose_round

log = logging.getLogger(__name__)


def keep_preferred(run: Run, teacher: Teacher, callback: RunCallback | None = None) -> int:
    """The round whose policy round `run.next_round` trains on from (module docstring),
    loaded into the agent when it is not the last round's; also set as
    `run.continued_from` for the round's record. -1 before round 0 (nothing to choose).

    Raises:
        ValueError: the run has no directory (the policies compared are its checkpoints).
    """
    if not run.records:
        return -1
    last = run.records[-1].round
    start = run.records[-1].continued_from
    chosen = last
    if 0 <= start < last:
        episodes_seed, teacher_rng = keep_streams(run.cfg.loop.seed, run.next_round)
        episodes = round_episodes(
            run, [start, last], run.cfg.training.continue_episodes, episodes_seed, callback, "keep"
        )
        choice = choose_round(episodes, teacher, teacher_rng)
        chosen = choice.round
        if chosen != last:
            run.ppo.revert(checkpoint_dir(run.directory, chosen))
        log.info(
            "round %d trains on from round %d's policy (teacher: round %d won %.2f, round %d "
            "%.2f of their comparisons)",
            run.next_round,
            chosen,
            start,
            choice.scores[0],
            last,
            choice.scores[1],
        )
    run.continued_from = chosen
    return chosen
