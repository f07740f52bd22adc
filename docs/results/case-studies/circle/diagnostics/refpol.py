"""PPO (MuJoCo settings, 204,800 steps, seed 1) on the backflip's own step score, saved to
/work/diag/refpol-hopper for rank.py.
"""

from pathlib import Path

from groupwise.config import PPO_PRESETS
from groupwise.envs import TARGETS, make_env
from groupwise.rl.ppo import PPOAgent
from groupwise.study.target_reference import ScoreAsReward

t = TARGETS["hopper-backflip"]
agent = PPOAgent(lambda: ScoreAsReward(make_env(t.env)), PPO_PRESETS["mujoco"], 1)
agent.learn(204800, 1)
agent.save(Path("/work/diag/refpol-hopper"))
print("saved")
