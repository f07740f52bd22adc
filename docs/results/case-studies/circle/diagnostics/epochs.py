"""Refit a run's final dataset from scratch for E epochs, 25 % of fragments held out: the
fit's correlation with the true returns of trained and held-out fragments.

    python epochs.py RUN_DIR E ...
"""

import dataclasses
import sys
from pathlib import Path

import numpy as np
import torch
from scipy.stats import pearsonr, spearmanr

from groupwise.config import RunConfig
from groupwise.envs import make_env
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward import RewardEnsemble
from groupwise.reward.bradley_terry import fit
from groupwise.run.checkpoint import DATASET_FILE, checkpoint_dir

torch.set_num_threads(1)
run = Path(sys.argv[1])
cfg = RunConfig.load(run / "config.json")
ds = PreferenceDataset.load(checkpoint_dir(run, 4) / DATASET_FILE)
rng = np.random.default_rng(0)
F = ds.n_fragments
test = rng.random(F) < 0.25
keep = ~(test[ds.pairs[:, 0]] | test[ds.pairs[:, 1]])
train = dataclasses.replace(
    ds, pairs=ds.pairs[keep], labels=ds.labels[keep], rounds=ds.rounds[keep]
)
print(
    run.name,
    "fragments",
    F,
    "pairs",
    len(ds),
    "train pairs",
    keep.sum(),
    "test fragments",
    test.sum(),
)
env_name = cfg.loop.env
for epochs in [int(e) for e in sys.argv[2:]]:
    for _rc_name, rc in [("default", cfg.reward)]:
        ens = RewardEnsemble.for_env(lambda: make_env(env_name), rc, np.random.default_rng(1))
        rep = fit(ens, train, rc, np.random.default_rng(2), epochs)
        pred = ens.returns(ds.obs, ds.acts).mean(axis=1)
        t = ds.true_returns
        print(
            f"  epochs {epochs:4d}: train corr {pearsonr(pred[~test], t[~test])[0]:.2f}  test corr {pearsonr(pred[test], t[test])[0]:.2f} spearman {spearmanr(pred[test], t[test])[0]:.2f}  l2 {ens.l2_weight:.1e}"
        )
