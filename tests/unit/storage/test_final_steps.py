"""A session's final phase: its PPO steps on the frozen reward, stored when it is created."""

from groupwise.storage import SessionSettings


def test_the_final_phase_defaults_to_two_rounds_of_ppo_and_is_stored() -> None:
    resolved = SessionSettings(ppo_steps_per_round=5_000).for_env("GridWorld")
    assert resolved.final_steps == 10_000
    cfg = resolved.run_config("GridWorld")
    assert (cfg.loop.final_steps, cfg.loop.decision_maker) == (10_000, "human")
    assert SessionSettings(final_steps=0).for_env("GridWorld").final_steps == 0


def test_sessions_stored_before_the_final_phase_get_the_default() -> None:
    old = SessionSettings.model_validate({"ppo_steps_per_round": 300, "fragment_length": 30})
    assert old.final_steps is None and old.final_ppo_steps == 600
    assert old.run_config("GridWorld").loop.final_steps == 600
    huge = SessionSettings(ppo_steps_per_round=9_000_000)
    assert huge.final_ppo_steps == 10_000_000  # bounded as any PPO phase of the app
