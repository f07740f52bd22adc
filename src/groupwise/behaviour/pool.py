"""A round's behaviour pool: the fragments on offer, what the ensemble predicts of them, and
their DTW distances and tree, each computed once (behaviour i is named ``b<i>``:
`groupwise.episodes.ids`). Sampling one from a policy is `groupwise.pool.sampling`'s job."""

from dataclasses import dataclass, field

import numpy as np

from groupwise.behaviour.dtw import band_window, dtw_matrix
from groupwise.behaviour.features import pool_features
from groupwise.behaviour.tree import BehaviourTree, build_tree
from groupwise.config import TreeConfig
from groupwise.episodes.fragments import Fragment, Trajectory
from groupwise.types import FloatArray, IntArray, ProgressFn


@dataclass(frozen=True)
class BehaviourPool:
    """The behaviours of one round.

    `predicted_returns` is computed once per round (SPEC §5) and shared by every query
    strategy: row i is behaviour i's predicted return under each ensemble member.
    `step_variance` is each behaviour's ensemble variance of its per-step rewards, averaged
    over its steps (`groupwise.query.groups.step_variance`), the intra term of the
    group-variance score; None when the pool was built without it (group active learning
    then falls back to `groupwise.query.groups.return_variance`). `episodes` are the whole
    episodes the fragments were cut from, when known: what replays them into clips.
    """

    round: int
    fragments: tuple[Fragment, ...]
    predicted_returns: FloatArray  # (N, K)
    step_variance: FloatArray | None = None  # (N,)
    episodes: tuple[Trajectory, ...] = field(default=(), repr=False)
    sources: IntArray | None = field(default=None, repr=False)
    """(N,) which source played each behaviour (its episode's `Trajectory.source`: 0 the
    round's policy, then the other sources' tags); taken from `episodes` when not given,
    None when neither is known."""
    _trees: dict[TreeConfig, BehaviourTree] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )
    _measured: dict[str, FloatArray] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        if self.sources is None and self.episodes:
            tags = {episode.episode: episode.source for episode in self.episodes}
            sources = np.array([tags.get(f.episode, -1) for f in self.fragments], np.int64)
            object.__setattr__(self, "sources", sources)
        if self.sources is not None and np.shape(self.sources) != (len(self.fragments),):
            shape = np.shape(self.sources)
            raise ValueError(f"{shape} sources for {len(self.fragments)} fragments")
        if self.predicted_returns.shape[0] != len(self.fragments):
            raise ValueError(
                f"{self.predicted_returns.shape[0]} predicted returns for "
                f"{len(self.fragments)} fragments"
            )
        if self.step_variance is not None and self.step_variance.shape != (len(self.fragments),):
            raise ValueError(
                f"step variance of shape {self.step_variance.shape} for "
                f"{len(self.fragments)} fragments"
            )

    def __len__(self) -> int:
        return len(self.fragments)

    @property
    def true_returns(self) -> FloatArray:
        """(N,) true return of each behaviour (for simulated users and evaluation only)."""
        return np.array([f.true_return for f in self.fragments])

    @property
    def distances(self) -> FloatArray:
        """Condensed DTW distances of the pool's behaviours (SPEC §4) with the default
        `TreeConfig`'s band and time step, computed once."""
        return self.measure_distances()

    def measure_distances(
        self, progress: ProgressFn | None = None, cfg: TreeConfig | None = None
    ) -> FloatArray:
        """The distances with `cfg`'s DTW band and time step (`TreeConfig.dtw_band`,
        `dtw_stride`; default config: `distances`), computed now unless they were before;
        `progress` hears (pairs done, pairs) while they are computed
        (`behaviour.dtw.dtw_matrix`)."""
        cfg = cfg or TreeConfig()
        key = f"distances/{cfg.dtw_band}/{cfg.dtw_stride}"
        if key not in self._measured:
            features = pool_features(self.fragments)
            window = band_window(cfg.dtw_band, max(len(f) for f in features))
            self._measured[key] = dtw_matrix(
                features, window=window, progress=progress, stride=cfg.dtw_stride
            )
        return self._measured[key]

    def tree(self, cfg: TreeConfig | None = None) -> BehaviourTree:
        """The pool's behaviour tree cut by `cfg` (SPEC §4), built once per config: the one
        tree the strategies' candidates, the published pool and the page share."""
        cfg = cfg or TreeConfig()
        if cfg not in self._trees:
            self._trees[cfg] = build_tree(self.measure_distances(cfg=cfg), cfg)
        return self._trees[cfg]
