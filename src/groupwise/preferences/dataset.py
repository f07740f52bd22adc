"""The cumulative preference dataset the reward model trains on.

Fragments are stored once each (as arrays) and pairs refer to them by row, so a fragment
used in many pairs costs its memory once. Saved as a plain `.npz` (no pickles).
"""

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from groupwise.episodes.fragments import Fragment
from groupwise.preferences.pairs import Pair
from groupwise.types import FloatArray, IntArray


@dataclass
class PreferenceDataset:
    """Fragments (F rows) and preference pairs (P rows) over them."""

    obs: FloatArray  # (F, L, obs_dim)
    acts: FloatArray  # (F, L, act_dim)
    true_returns: FloatArray  # (F,)
    pairs: IntArray  # (P, 2) rows into the fragment arrays
    labels: FloatArray  # (P,) probability that the first fragment is preferred
    rounds: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))  # (P,)

    @classmethod
    def empty(cls, length: int, obs_dim: int, act_dim: int) -> "PreferenceDataset":
        return cls(
            obs=np.zeros((0, length, obs_dim), dtype=np.float32),
            acts=np.zeros((0, length, act_dim), dtype=np.float32),
            true_returns=np.zeros(0, dtype=np.float64),
            pairs=np.zeros((0, 2), dtype=np.int64),
            labels=np.zeros(0, dtype=np.float32),
            rounds=np.zeros(0, dtype=np.int64),
        )

    def __len__(self) -> int:
        return int(self.pairs.shape[0])

    @property
    def n_fragments(self) -> int:
        return int(self.obs.shape[0])

    def add(self, pool: Sequence[Fragment], pairs: Sequence[Pair], round_index: int) -> None:
        """Append `pairs` over `pool` (indices into `pool`), storing each used fragment once."""
        if not pairs:
            return
        used = sorted({p.a for p in pairs} | {p.b for p in pairs})
        row = {index: self.n_fragments + k for k, index in enumerate(used)}
        self.obs = np.concatenate([self.obs, np.stack([pool[i].obs for i in used])])
        self.acts = np.concatenate([self.acts, np.stack([pool[i].acts for i in used])])
        returns = np.array([pool[i].true_return for i in used])
        self.true_returns = np.concatenate([self.true_returns, returns])
        new_pairs = np.array([[row[p.a], row[p.b]] for p in pairs], dtype=np.int64)
        self.pairs = np.concatenate([self.pairs, new_pairs])
        self.labels = np.concatenate([self.labels, [p.label for p in pairs]]).astype(np.float32)
        self.rounds = np.concatenate([self.rounds, np.full(len(pairs), round_index)])

    def label_error_rate(self, mask: np.ndarray | None = None, *, untied: bool = False) -> float:
        """Share of labels (of the pairs in `mask`, default all) that disagree with the true
        returns; nan when there are none.

        With `untied`, only pairs whose true returns differ count: a label other than 0.5 on
        exactly equal returns (common where a target score is 0 for most behaviours) is
        arbitrary rather than wrong about which is better.
        """
        keep = np.ones(len(self), dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        if untied:
            keep = keep & ~self.tied()
        pairs, labels = self.pairs[keep], self.labels[keep]
        if len(pairs) == 0:
            return float("nan")
        returns = self.true_returns
        return float(wrong_labels(returns[pairs[:, 0]], returns[pairs[:, 1]], labels).mean())

    def tied(self) -> np.ndarray:
        """(P,) bool: which pairs join two behaviours of exactly equal true return."""
        returns = self.true_returns
        return np.asarray(returns[self.pairs[:, 0]] == returns[self.pairs[:, 1]])

    def save(self, path: Path) -> None:
        np.savez_compressed(
            path,
            obs=self.obs,
            acts=self.acts,
            true_returns=self.true_returns,
            pairs=self.pairs,
            labels=self.labels,
            rounds=self.rounds,
        )

    @classmethod
    def load(cls, path: Path) -> "PreferenceDataset":
        with np.load(path, allow_pickle=False) as data:
            return cls(**{key: data[key] for key in data.files})


def wrong_labels(return_a: FloatArray, return_b: FloatArray, labels: FloatArray) -> np.ndarray:
    """(P,) bool: which labels disagree with the true returns of their pairs.

    A label of 1.0 is right when a's true return is higher, 0.0 when it is lower, and 0.5
    only when both are exactly equal.
    """
    diff = np.asarray(return_a) - np.asarray(return_b)
    truth = np.where(diff > 0, 1.0, np.where(diff < 0, 0.0, 0.5))
    return np.asarray(truth != np.asarray(labels))
