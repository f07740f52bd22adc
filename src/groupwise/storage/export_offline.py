"""A session's preference pairs in the files offline preference learners read (issue 42).

Two formats, documented for their readers in docs/export.md:

- ``ipl-npz``: one ``.npz`` in the layout of IPL's and CPL's
  ``scripts/create_comparison_dataset.py`` (jhejna/inverse-preference-learning,
  jhejna/cpl): ``obs_1``, ``obs_2`` (N, L, obs_dim) float32, ``action_1``, ``action_2``
  (N, L, act_dim) float32, ``label`` (N,) float32 and, when the true rewards are exported,
  ``reward_1``, ``reward_2`` (N, L) float32 (CPL's ``FeedbackBuffer`` reads them; IPL does
  not). Their label is 1 when the *second* segment is preferred: IPL writes
  ``label = 1.0 * (return_1 < return_2)`` and CPL reads ``label`` as segment 2's score
  against ``1 - label`` for segment 1, so ``label = 1 - P(first preferred)``: 0 when the
  first is preferred, 1 when the second is, 0.5 when they were judged equal.
- ``pt-indices``: a directory for the index pickles of Preference Transformer
  (csmile-1006/PreferenceTransformer, ``human_label/<env>/``: ``indices_num<N>``,
  ``indices_2_num<N>``, ``label_human``) and of Uni-RLHF's Clean-Offline-RLHF
  (``<env>_human_labels/``: ``indices_1_<suffix>.pkl``, ``indices_2_<suffix>.pkl``,
  ``human_label_<suffix>.pkl``, suffix ``domain_<d>_env_<env>_num_<N>_len_<L>_<id>``). The
  indices are start rows of each pair's two segments in a D4RL-style flat dataset, which
  both read with ``dataset["observations"][start:start + L]``; groupwise's behaviours were
  never such a dataset, so the export writes one, ``dataset.npz``: every compared
  behaviour once, L consecutive rows each, with ``observations``, ``actions``, ``rewards``
  (NaN when the true rewards are withheld), ``terminals`` (all False) and ``timeouts`` (True
  on each behaviour's last row). Labels are both projects' codes: 0 the first segment
  preferred, 1 the second, -1 equal.

Pairs are those of the judgements not undone, round by round and in judgement order within a
round, the order `groupwise.storage.states.preference_dataset` gives the reward model.
"""

import io
import pickle
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from groupwise.storage.errors import InvalidError
from groupwise.storage.export_format import SessionExport
from groupwise.types import FloatArray, IntArray

EQUAL_CODE = -1
"""PT's and Uni-RLHF's label for two segments judged equal (0: first, 1: second better)."""

DOMAIN = "groupwise"
"""The ``domain_<d>`` of Uni-RLHF's file names."""


@dataclass(frozen=True)
class OfflinePairs:
    """A session's N preference pairs of L-step behaviours with both behaviours' arrays."""

    env: str
    session_id: str
    obs_1: FloatArray  # (N, L, obs_dim) float32, the first behaviour's observations
    obs_2: FloatArray  # (N, L, obs_dim) float32
    action_1: FloatArray  # (N, L, act_dim) float32, encoded actions (one-hot for Discrete)
    action_2: FloatArray  # (N, L, act_dim) float32
    reward_1: FloatArray | None  # (N, L) float64 true rewards; None when withheld
    reward_2: FloatArray | None  # (N, L) float64
    first_preferred: FloatArray  # (N,) float32 P(first preferred): 1, 0.5 or 0
    behaviour_1: tuple[tuple[int, str], ...]  # (N,) (round, "b<i>") of the first behaviour
    behaviour_2: tuple[tuple[int, str], ...]  # (N,)

    def __len__(self) -> int:
        return len(self.first_preferred)

    @property
    def length(self) -> int:
        """L, steps per behaviour."""
        return int(self.obs_1.shape[1])


def offline_pairs(export: SessionExport) -> OfflinePairs:
    """The pairs of an export with states (module docstring for their order).

    Raises:
        InvalidError: the export holds no states, or no pair.
    """
    by_round = {states.round: states for states in export.behaviours}
    live = [j for j in export.judgements if not j.undone and j.pairs]
    if not live:
        raise InvalidError(f"session {export.session.id} has no preference pairs to export")
    if not by_round:
        raise InvalidError("the export holds no behaviour states (export with states)")
    ordered = sorted(live, key=lambda j: j.round)  # stable: judgement order within a round
    firsts, seconds, labels = [], [], []
    for judgement in ordered:
        for pair in judgement.pairs:
            firsts.append((judgement.round, pair.a))
            seconds.append((judgement.round, pair.b))
            labels.append(pair.label)
    rewards = all(states.true_rewards is not None for states in by_round.values())

    def gather(keys: list[tuple[int, str]]) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        obs, acts, true = [], [], []
        for round_index, name in keys:
            states = by_round.get(round_index)
            if states is None:
                raise InvalidError(f"the export has no states of round {round_index}")
            row = states.row(name)
            obs.append(states.obs[row])
            acts.append(states.acts[row])
            if rewards:
                true.append(states.true_rewards[row])  # type: ignore[index]  # checked above
        stacked = np.stack(true).astype(np.float64) if rewards else None
        return np.stack(obs).astype(np.float32), np.stack(acts).astype(np.float32), stacked

    obs_1, action_1, reward_1 = gather(firsts)
    obs_2, action_2, reward_2 = gather(seconds)
    return OfflinePairs(
        env=export.session.env,
        session_id=export.session.id,
        obs_1=obs_1,
        obs_2=obs_2,
        action_1=action_1,
        action_2=action_2,
        reward_1=reward_1,
        reward_2=reward_2,
        first_preferred=np.asarray(labels, dtype=np.float32),
        behaviour_1=tuple(firsts),
        behaviour_2=tuple(seconds),
    )


def to_ipl_npz(pairs: OfflinePairs) -> bytes:
    """The ``ipl-npz`` bytes of `pairs` (module docstring), uncompressed ``np.savez``."""
    arrays: dict[str, np.ndarray] = {
        "obs_1": pairs.obs_1,
        "obs_2": pairs.obs_2,
        "action_1": pairs.action_1,
        "action_2": pairs.action_2,
        "label": (1.0 - pairs.first_preferred).astype(np.float32),
    }
    if pairs.reward_1 is not None and pairs.reward_2 is not None:
        arrays["reward_1"] = pairs.reward_1.astype(np.float32)
        arrays["reward_2"] = pairs.reward_2.astype(np.float32)
    sink = io.BytesIO()
    np.savez(sink, **arrays)  # type: ignore[arg-type]  # numpy's stub wants one array type
    return sink.getvalue()


def index_codes(first_preferred: FloatArray) -> IntArray:
    """PT's and Uni-RLHF's label codes of P(first preferred): 1 → 0, 0 → 1, 0.5 → -1.

    Raises:
        InvalidError: a label of any other value (they have no code for it).
    """
    codes = np.full(len(first_preferred), EQUAL_CODE, dtype=np.int64)
    codes[first_preferred == 1.0] = 0
    codes[first_preferred == 0.0] = 1
    odd = ~np.isin(first_preferred, (0.0, 0.5, 1.0))
    if odd.any():
        raise InvalidError(
            f"pair {int(np.argmax(odd))} has label {float(first_preferred[odd][0]):g}: index "
            "pickles hold only 0 (first better), 1 (second better) and -1 (equal)"
        )
    return codes


def env_slug(env: str) -> str:
    """An env name as one path component: ``dm_control/walker-walk-v0`` →
    ``dm_control-walker-walk-v0``, ``pkg:Env-v0`` → ``pkg-Env-v0``."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", env).strip("-") or "env"


def write_pt_indices(pairs: OfflinePairs, directory: Path) -> list[Path]:
    """Write the ``pt-indices`` layout (module docstring) into `directory` (made if
    missing); the files written, dataset first.

    Raises:
        InvalidError: a label with no index code (`index_codes`).
    """
    codes = index_codes(pairs.first_preferred)
    rows: dict[tuple[int, str], int] = {}
    obs: list[FloatArray] = []
    acts: list[FloatArray] = []
    rewards: list[FloatArray] = []
    length = pairs.length
    sides = (
        (pairs.behaviour_1, pairs.obs_1, pairs.action_1, pairs.reward_1),
        (pairs.behaviour_2, pairs.obs_2, pairs.action_2, pairs.reward_2),
    )
    starts = np.zeros((2, len(pairs)), dtype=np.int64)
    for i in range(len(pairs)):
        for side, (keys, side_obs, side_acts, side_rewards) in enumerate(sides):
            key = keys[i]
            if key not in rows:
                rows[key] = len(rows) * length
                obs.append(side_obs[i])
                acts.append(side_acts[i])
                rewards.append(np.full(length, np.nan) if side_rewards is None else side_rewards[i])
            starts[side, i] = rows[key]
    timeouts = np.zeros(len(rows) * length, dtype=bool)
    timeouts[length - 1 :: length] = True
    directory.mkdir(parents=True, exist_ok=True)
    dataset = directory / "dataset.npz"
    np.savez(
        dataset,
        observations=np.concatenate(obs).astype(np.float32),
        actions=np.concatenate(acts).astype(np.float32),
        rewards=np.concatenate(rewards).astype(np.float32),
        terminals=np.zeros(len(timeouts), dtype=bool),
        timeouts=timeouts,
    )
    env, n = env_slug(pairs.env), len(pairs)
    pt = directory / "human_label" / env
    suffix = f"_domain_{DOMAIN}_env_{env}_num_{n}_len_{length}_{pairs.session_id}.pkl"
    uni = directory / f"{env}_human_labels"
    files = {
        pt / f"indices_num{n}": starts[0],
        pt / f"indices_2_num{n}": starts[1],
        pt / "label_human": codes,
        uni / f"indices_1{suffix}": starts[0],
        uni / f"indices_2{suffix}": starts[1],
        uni / f"human_label{suffix}": codes,
    }
    for path, array in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(pickle.dumps(array))
    return [dataset, *files]
