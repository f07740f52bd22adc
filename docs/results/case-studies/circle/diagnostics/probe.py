"""A Hopper backflip run's learned reward (round ROUND) read on the states of its dataset: its
correlation with each observation dimension, and the mean change when the pitch is moved by a
whole turn, in sd of the reward.

    python probe.py RUN_DIR ROUND
"""

import sys
from pathlib import Path

import numpy as np

from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward import RewardEnsemble
from groupwise.run.checkpoint import DATASET_FILE, REWARD_FILE, checkpoint_dir

run = Path(sys.argv[1])
r = int(sys.argv[2])
ds = PreferenceDataset.load(checkpoint_dir(run, 4) / DATASET_FILE)
ens = RewardEnsemble.load(checkpoint_dir(run, r) / REWARD_FILE)
obs = ds.obs
acts = ds.acts
print(obs.shape)
F, L, D = obs.shape
rew = ens.mean_reward(obs.reshape(F * L, D), acts.reshape(F * L, -1))
o = obs.reshape(F * L, D)
names = ["z", "pitch", "thigh", "leg", "foot", "vx", "vz", "w", "vthigh", "vleg", "vfoot"]
for i, n in enumerate(names[:D]):
    print(
        f"{n:7s} corr {np.corrcoef(rew, o[:, i])[0, 1]:+.2f}  range {o[:, i].min():+.2f}..{o[:, i].max():+.2f}"
    )
# linear fit
X = np.c_[o, np.ones(len(o))]
coef, *_ = np.linalg.lstsq(X, rew, rcond=None)
pred = X @ coef
print("linear R2", 1 - ((rew - pred) ** 2).mean() / rew.var())
# probe: lying on back vs rotating
sd = rew.std()
for shift in (-2 * np.pi, -np.pi, np.pi):
    o2 = o.copy()
    o2[:, 1] += shift
    r2 = ens.mean_reward(o2, acts.reshape(F * L, -1))
    print(f"pitch {shift:+.2f}: mean reward change {(r2 - rew).mean() / sd:+.2f} sd")
# members separately
