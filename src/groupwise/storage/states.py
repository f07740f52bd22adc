"""The judged behaviours' states (observations, encoded actions, true rewards) and the
preference dataset of a session's stored pairs over them.

A behaviour's arrays live in its round's pool directory (``behaviours.npz``, the format of
`groupwise.pool.files`, read here with numpy alone, so the server needs no RL code) or, for
a session imported from an export with states, in ``states.npz`` of the imported round's
directory (``DIR/sessions/<id>/round-<r>/``), which `write_round_states` writes. Either way
`read_round_states` gives the same `BehaviourStates`, and `preference_dataset` turns a
session's stored pairs into the `PreferenceDataset` a reward model fits
(`groupwise.reward.bradley_terry.fit`), without the original pool directories.
"""

from collections.abc import Iterable
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np
from sqlalchemy.orm import Session as DbSession

from groupwise.episodes.ids import behaviour_index
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.storage.errors import InvalidError, NotFoundError
from groupwise.storage.judgements import list_judgements
from groupwise.storage.sessions import get_round, round_directory
from groupwise.types import FloatArray

POOL_ARRAYS = "behaviours.npz"
"""A published pool's arrays (`groupwise.pool.files`): obs, acts, true_rewards by index."""
STATES_FILE = "states.npz"
"""An imported round's arrays: names, obs, acts and (when exported) true_rewards."""


@dataclass(frozen=True)
class BehaviourStates:
    """Some behaviours of one round, each a window of L steps."""

    round: int
    names: tuple[str, ...]  # (B,) "b<i>", the pool's ids
    obs: FloatArray  # (B, L, obs_dim) float32, the observation before each step
    acts: FloatArray  # (B, L, act_dim) float32, encoded actions (one-hot for Discrete)
    true_rewards: FloatArray | None  # (B, L) float64 env rewards; None when not exported

    def __post_init__(self) -> None:
        b = len(self.names)
        if self.obs.ndim != 3 or self.acts.ndim != 3:
            raise InvalidError(f"round {self.round}: obs and acts must be (B, L, dim) arrays")
        if self.obs.shape[:2] != self.acts.shape[:2] or self.obs.shape[0] != b:
            raise InvalidError(
                f"round {self.round}: {b} behaviours but obs {self.obs.shape}, acts "
                f"{self.acts.shape}"
            )
        if self.true_rewards is not None and self.true_rewards.shape != self.obs.shape[:2]:
            raise InvalidError(
                f"round {self.round}: true_rewards {self.true_rewards.shape} do not match "
                f"obs {self.obs.shape}"
            )
        if len(set(self.names)) != b:
            raise InvalidError(f"round {self.round} lists a behaviour twice")

    def row(self, name: str) -> int:
        """The row of behaviour `name`. Raises InvalidError when it is not here."""
        try:
            return self.names.index(name)
        except ValueError:
            raise InvalidError(f"the states of round {self.round} lack {name}") from None


def read_round_states(
    data_dir: str | PathLike[str],
    session_id: str,
    round_index: int,
    pool_dir: str | None,
    names: Iterable[str],
) -> BehaviourStates:
    """The states of behaviours `names` of a session's round, in the order given.

    Reads an imported round's ``states.npz`` if there is one, else the round's pool
    (`pool_dir`, relative to `data_dir` and never outside it). Raises NotFoundError when
    neither exists (a pool directory deleted, or a session imported without states),
    InvalidError when a name is not in it.
    """
    wanted = tuple(names)
    root = Path(data_dir).resolve()
    imported = root / round_directory(session_id, round_index) / STATES_FILE
    # only ever inside the data directory: an imported export's pool_dir could name any path
    pool = (root / pool_dir / POOL_ARRAYS).resolve() if pool_dir else None
    if pool is not None and not pool.is_relative_to(root):
        pool = None
    if imported.is_file():
        with np.load(imported) as data:
            stored = BehaviourStates(
                round_index,
                tuple(str(n) for n in data["names"]),
                data["obs"],
                data["acts"],
                data["true_rewards"] if "true_rewards" in data else None,
            )
        rows = [stored.row(name) for name in wanted]
    elif pool is not None and pool.is_file():
        with np.load(pool) as data:
            obs, acts, rewards = data["obs"], data["acts"], data["true_rewards"]
        stored = BehaviourStates(
            round_index, tuple(f"b{i}" for i in range(len(obs))), obs, acts, rewards
        )
        rows = [_index_in(name, len(obs), round_index) for name in wanted]
    else:
        raise NotFoundError(
            f"the behaviours of round {round_index} of session {session_id} are not in "
            f"the data directory (no {STATES_FILE}, no pool at {pool_dir})"
        )
    rewards = None if stored.true_rewards is None else stored.true_rewards[rows]
    return BehaviourStates(round_index, wanted, stored.obs[rows], stored.acts[rows], rewards)


def _index_in(name: str, size: int, round_index: int) -> int:
    index = behaviour_index(name)
    if not 0 <= index < size:
        raise InvalidError(f"the pool of round {round_index} has no behaviour {name}")
    return index


def write_round_states(directory: Path, states: BehaviourStates) -> None:
    """Write an imported round's ``states.npz`` into `directory` (made if missing)."""
    directory.mkdir(parents=True, exist_ok=True)
    arrays: dict[str, np.ndarray] = {
        "names": np.array(states.names, dtype=str),
        "obs": states.obs,
        "acts": states.acts,
    }
    if states.true_rewards is not None:
        arrays["true_rewards"] = states.true_rewards
    tmp = directory / f"{STATES_FILE}.tmp.npz"
    np.savez(tmp, **arrays)  # type: ignore[arg-type]  # numpy's stub: **kwds may hit allow_pickle
    tmp.replace(directory / STATES_FILE)


def preference_dataset(
    s: DbSession, data_dir: str | PathLike[str], session_id: str
) -> PreferenceDataset:
    """The session's stored pairs (of judgements not undone) over their behaviours' states:
    each behaviour of a round stored once, pairs in judgement order, `rounds` their round.

    Every stored pair is taken (a session's `pair_cap`, which `end_round` applies per round,
    is not). Raises NotFoundError (no session, or a round's states are missing),
    InvalidError (states and pairs disagree); an empty dataset needs at least one pair.
    """
    judgements = list_judgements(s, session_id)
    by_round: dict[int, list[tuple[str, str, float]]] = {}
    for j in judgements:
        by_round.setdefault(j.round, []).extend((p.a, p.b, p.label) for p in j.pairs)
    obs: list[FloatArray] = []
    acts: list[FloatArray] = []
    returns: list[FloatArray] = []
    pairs: list[list[int]] = []
    labels: list[float] = []
    rounds: list[int] = []
    offset = 0
    for round_index, round_pairs in sorted(by_round.items()):
        if not round_pairs:
            continue
        names = sorted({n for a, b, _ in round_pairs for n in (a, b)}, key=behaviour_index)
        pool_dir = get_round(s, session_id, round_index).pool_dir
        states = read_round_states(data_dir, session_id, round_index, pool_dir, names)
        row = {name: offset + k for k, name in enumerate(names)}
        obs.append(states.obs.astype(np.float32))
        acts.append(states.acts.astype(np.float32))
        returns.append(
            np.full(len(names), np.nan)
            if states.true_rewards is None
            else states.true_rewards.sum(axis=1)
        )
        pairs.extend([row[a], row[b]] for a, b, _ in round_pairs)
        labels.extend(label for _, _, label in round_pairs)
        rounds.extend([round_index] * len(round_pairs))
        offset += len(names)
    if not obs:
        raise NotFoundError(f"session {session_id} has no preference pairs")
    return PreferenceDataset(
        obs=np.concatenate(obs),
        acts=np.concatenate(acts),
        true_returns=np.concatenate(returns).astype(np.float64),
        pairs=np.asarray(pairs, dtype=np.int64).reshape(-1, 2),
        labels=np.asarray(labels, dtype=np.float32),
        rounds=np.asarray(rounds, dtype=np.int64),
    )
