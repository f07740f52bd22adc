"""Fault injection under load, shortened (`python -m benchmarks faults` runs 100 trials):
a real server and its worker are SIGKILLed at random moments while clients submit
judgements; the database must hold every answered judgement once, whole, as sent. In
continuous sessions (the app's default) the worker is killed while it trains PPO, refits,
prepares the next round ahead or commits a round after opening the next."""

import pytest
from benchmarks.faults import FaultConfig, run


@pytest.mark.parametrize("training", ["continuous", "rounds"])
def test_kills_of_server_and_worker_lose_duplicate_and_half_store_nothing(training):
    config = FaultConfig(trials=4, clients=3, seed=1, load_s=(0.2, 1.0), training=training)
    outcome = run(config)
    audit = outcome.audit
    assert min(outcome.kills.values()) > 0, outcome.kills  # seed 1 draws both kinds
    assert audit.acknowledged > 20, audit
    problems = "\n".join(audit.problems + tuple(outcome.failures))
    assert (audit.lost, audit.duplicated, audit.half_stored, audit.altered) == (0, 0, 0, 0), (
        problems
    )
    assert audit.server_errors == 0, problems
    assert audit.orphans == 0, problems
    assert outcome.stuck == 0 and not outcome.failures, problems
    assert outcome.usable_at_end  # the session resumed: one more judgement is taken
