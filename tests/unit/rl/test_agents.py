import tempfile

from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.logger import Logger

from groupwise.envs import make_env
from groupwise.rl.agents import as_agent


def _model(**kwargs):
    venv = make_vec_env(lambda: make_env("MountainCarContinuous"), n_envs=1)
    return PPO("MlpPolicy", venv, n_steps=64, batch_size=32, n_epochs=1, device="cpu", **kwargs)


def test_a_users_sb3_model_learns_without_temp_folders(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    agent = as_agent(_model())
    agent.learn(64, seed=1)
    agent.learn(64, seed=2)
    assert agent.num_timesteps == 128
    assert not list(tmp_path.glob("SB3-*"))  # SB3 alone makes one such folder per call


def test_a_users_own_logger_is_kept(tmp_path):
    model = _model()
    own = Logger(folder=str(tmp_path), output_formats=[])
    model.set_logger(own)
    as_agent(model).learn(64, seed=1)
    assert model.logger is own
