"""The app's worker opens a session's run as a headless run begins: a fresh one runs the
config's setup hooks (state-entropy pre-training), the same way for a seed."""

from groupwise.storage.settings import SessionSettings
from groupwise.worker.job import Job, open_run

RESEARCH = {"ppo": {"n_envs": 1, "n_steps": 64, "batch_size": 32, "n_epochs": 1}}


def _job(settings: SessionSettings) -> Job:
    return Job(
        session_id="s-pretrain",
        env="GridWorld",
        mode="groupwise",
        phase="preparing",
        round=0,
        settings=settings,
        elapsed_s=0.0,
    )


def test_a_fresh_session_run_pretrains_when_its_settings_ask(tmp_path):
    plain = open_run(_job(SessionSettings(research=RESEARCH)), tmp_path / "plain", after=-1)
    with plain:
        assert plain.agent.num_timesteps == 0
    settings = SessionSettings(pretrain_steps=128, research=RESEARCH)
    with open_run(_job(settings), tmp_path / "pre", after=-1) as run:
        assert run.cfg.training.pretrain_steps == 128
        assert run.agent.num_timesteps >= 128  # whole rollouts of 64 steps
        steps = run.agent.num_timesteps
        first = {k: v.clone() for k, v in run.ppo.model.policy.state_dict().items()}
    with open_run(_job(settings), tmp_path / "again", after=-1) as again:  # the same, seeded
        assert again.agent.num_timesteps == steps
        weights = again.ppo.model.policy.state_dict()
        assert all(weights[k].equal(v) for k, v in first.items())


def test_a_session_pretrains_once_for_round_0(tmp_path, caplog):
    """The job preparing round 0 and the one ending it both open the fresh run: the first
    pre-trains and keeps the agent (checkpoints/pretrained), the second loads it."""
    settings = SessionSettings(pretrain_steps=128, research=RESEARCH)
    caplog.set_level("INFO", logger="groupwise.run.pretrain")
    with open_run(_job(settings), tmp_path, after=-1) as prepared:  # prepare round 0
        steps = prepared.agent.num_timesteps
        first = {k: v.clone() for k, v in prepared.ppo.model.policy.state_dict().items()}
    with open_run(_job(settings), tmp_path, after=-1) as ending:  # end round 0
        assert ending.agent.num_timesteps == steps >= 128
        weights = ending.ppo.model.policy.state_dict()
        assert all(weights[k].equal(v) for k, v in first.items())
    pretrained = [r for r in caplog.records if "pre-trained" in r.getMessage()]
    assert len(pretrained) == 1
