"""A state-entropy bonus for unsupervised pre-training before round 0 (issue 20).

PEBBLE (Lee et al. 2021, §4.1; B-Pref's ``compute_state_entropy``) pre-trains the policy on
an intrinsic reward that estimates the entropy of the visited states with the particle
(k-nearest-neighbour) estimator: a state far from its k-th nearest neighbour among recent
states lies in a sparsely visited region, r_int(s) = log(c + ‖s − s_k‖). A policy that
maximises it spreads its states out, so round 0's pool shows more different behaviours than a
random policy's (a random cheetah raises its front by at most 24°, docs/case-studies.md).

The estimate is pure (`knn_distance`, `entropy_bonus`); `StateEntropyReward` is the stateful
`RewardFn` PPO is paid with: a first-in-first-out buffer of the states it was shown, a k-d
tree over them rebuilt every `rebuild_every` states, and the bonus divided by its running
standard deviation (PEBBLE's ``s_ent_stats``). It draws nothing at random, so its rewards
are fixed by the states it sees.

States are compared after dividing each dimension by its standard deviation over the
reference states (our choice, as SPEC §4 makes it for behaviour distances): raw MuJoCo
observations mix angles (≈ 1) with joint velocities (≈ 10), and raw distances would pay
only for flailing.
"""

import numpy as np
from scipy.spatial import cKDTree

from groupwise.types import FloatArray

K_NEIGHBOUR = 5
"""k of the particle estimate: PEBBLE's and B-Pref's default."""
OFFSET = 1.0
"""c in log(c + distance): keeps the bonus finite where states repeat (APT, PEBBLE)."""


def standardised(states: FloatArray, reference: FloatArray) -> tuple[FloatArray, FloatArray]:
    """`states` (B, D) and `reference` (M, D) divided per dimension by the reference's sd
    (dimensions that never vary are left as they are)."""
    scale = reference.std(axis=0)
    scale = np.where(scale > 1e-8, scale, 1.0)
    return states / scale, reference / scale


def knn_distance(
    states: FloatArray,
    reference: FloatArray | cKDTree,
    k: int = K_NEIGHBOUR,
    *,
    exclude_self: bool = False,
) -> FloatArray:
    """Euclidean distance (B,) of each of `states` (B, D) to its k-th nearest neighbour
    among `reference` (M, D, or a k-d tree over them). With `exclude_self` the states are
    among the reference and their zero distance to themselves is not counted (B-Pref's
    ``kthvalue(k + 1)``).

    Raises:
        ValueError: k < 1, or fewer than k (k + 1 with `exclude_self`) reference states.
    """
    tree = reference if isinstance(reference, cKDTree) else cKDTree(reference)
    rank = k + 1 if exclude_self else k
    if k < 1 or tree.n < rank:
        raise ValueError(f"need k >= 1 and at least {rank} reference states, got {tree.n}")
    distances, _ = tree.query(np.asarray(states, dtype=np.float64), k=[rank])
    return np.asarray(distances[:, 0], dtype=np.float64)


def entropy_bonus(
    states: FloatArray,
    reference: FloatArray,
    k: int = K_NEIGHBOUR,
    c: float = OFFSET,
    *,
    exclude_self: bool = False,
) -> FloatArray:
    """The particle estimate's per-state term r(s) = log(c + ‖s − s_k‖) (B,), s_k the k-th
    nearest neighbour of s among `reference` (M, D), both standardised by the reference's
    per-dimension sd (`standardised`). Larger for states in sparser regions; its mean over a
    batch compared with itself (`exclude_self`) grows with the batch's spread.

    Raises:
        ValueError: as `knn_distance`.
    """
    scaled, ref = standardised(np.asarray(states, np.float64), np.asarray(reference, np.float64))
    return np.log(c + knn_distance(scaled, ref, k, exclude_self=exclude_self))


class StateEntropyReward:
    """A `RewardFn` paying each state its `entropy_bonus` against the last `capacity`
    states it was shown, divided by the running sd of every bonus paid so far.

    The k-d tree (and the per-dimension scale) is rebuilt once `rebuild_every` new states
    have arrived, so a call costs one query of B states; until k states have been seen the
    bonus is 0. `bonus_means` holds the mean raw bonus (before the sd) of each block of
    `rebuild_every` states. Each block is measured against the recent states in their own
    sd, so it says how evenly the policy covers what it visits, not how far it goes: it
    falls while the buffer fills (fewer, farther neighbours at first) and is not comparable
    across envs.
    """

    def __init__(
        self,
        k: int = K_NEIGHBOUR,
        c: float = OFFSET,
        capacity: int = 10_000,
        rebuild_every: int = 1024,
    ) -> None:
        if k < 1 or capacity < k or rebuild_every < 1:
            raise ValueError(f"need 1 <= k <= capacity and rebuild_every >= 1, got {k}, {capacity}")
        self.k, self.c, self.capacity, self.rebuild_every = k, c, capacity, rebuild_every
        self._buffer: np.ndarray | None = None  # (capacity, D), a ring
        self._filled = 0
        self._next = 0
        self._since_build = 0
        self._tree: cKDTree | None = None
        self._scale: np.ndarray | None = None
        self._block: list[float] = []
        self.bonus_means: list[float] = []
        self._count, self._mean, self._m2 = 0, 0.0, 0.0  # the bonus's running moments

    def __call__(self, obs: FloatArray, acts: FloatArray) -> FloatArray:
        """The normalised bonus (B,) of `obs` (B, D); `acts` are not used."""
        del acts
        states = np.asarray(obs, dtype=np.float64).reshape(len(obs), -1)
        if self._tree is None or self._since_build >= self.rebuild_every:
            self._build()
        raw = np.zeros(len(states))
        if self._tree is not None and self._scale is not None:
            distance = knn_distance(states / self._scale, self._tree, self.k)
            raw = np.log(self.c + distance)
            self._record(raw)
        self._remember(states)
        sd = np.sqrt(self._m2 / self._count) if self._count > 1 else 1.0
        return (raw / max(sd, 1e-8)).astype(np.float32)

    def _build(self) -> None:
        if self._buffer is None or self._filled < self.k:
            return
        reference = self._buffer[: self._filled]
        scale = reference.std(axis=0)
        self._scale = np.where(scale > 1e-8, scale, 1.0)
        self._tree = cKDTree(reference / self._scale)
        self._since_build = 0

    def _remember(self, states: np.ndarray) -> None:
        if self._buffer is None:
            self._buffer = np.zeros((self.capacity, states.shape[1]))
        self._buffer[(self._next + np.arange(len(states))) % self.capacity] = states
        self._next = (self._next + len(states)) % self.capacity
        self._filled = min(self._filled + len(states), self.capacity)
        self._since_build += len(states)

    def _record(self, raw: np.ndarray) -> None:
        # Chan et al.'s update of the running moments by a batch
        n, mean = len(raw), float(raw.mean())
        total = self._count + n
        delta = mean - self._mean
        self._m2 += float(((raw - mean) ** 2).sum()) + delta**2 * self._count * n / total
        self._mean += delta * n / total
        self._count = total
        self._block.extend(raw.tolist())
        if len(self._block) >= self.rebuild_every:
            self.bonus_means.append(float(np.mean(self._block)))
            self._block = []
