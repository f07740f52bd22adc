"""A run: the RLHF loop's mutable state and, when it has one, its directory.

`Run` owns everything a run persists — ``config.json``, one checkpoint per round
(`groupwise.run.checkpoint`), ``rounds.csv``, TensorBoard logs under ``tb/`` — and is the one
way `groupwise train`, the case studies, the final phase and the app's worker write them:

    run = Run.create(cfg, out)          # our PPO, a fresh reward ensemble; writes config.json
    run.restore()                       # the latest checkpoint (or `restore(after=r)`)
    ... a round (`groupwise.run.round`) ...
    run.commit()                        # checkpoint of the last round + rounds.csv
    run.close()

A user's own env factory and agent come in through `Run.of` (the library,
`groupwise.run.preference_comparisons`), which persists nothing unless given a directory.
"""

import dataclasses
import json
import logging
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from groupwise.config import RunConfig
from groupwise.envs import make_env
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward import RewardEnsemble
from groupwise.rl.agents import Agent
from groupwise.rl.ppo import PPOAgent
from groupwise.rl.rollout import EnvFactory
from groupwise.run.checkpoint import (
    CHECKPOINTS,
    DATASET_FILE,
    REWARD_FILE,
    STATE_FILE,
    checkpoint_dir,
    latest_checkpoint,
    write_checkpoint,
)
from groupwise.run.kept_policy import KeptPolicy
from groupwise.run.records import RoundRecord, read_record, write_records
from groupwise.run.streams import init_rng

log = logging.getLogger(__name__)

CONFIG_FILE = "config.json"
RESULTS_FILE = "rounds.csv"
TENSORBOARD_DIR = "tb"
MID_ROUND_DIR = "live"
"""``checkpoints/live``: a continuous round's policy and reward model mid-round (the folder
keeps its name from before issue 38, so a session stopped mid-round still resumes there)."""


class ConfigMismatchError(ValueError):
    """A run directory was written by a different configuration than the one resuming it."""


@dataclass
class Run:
    """The state of one RLHF run (what a checkpoint saves) and its directory `out`."""

    cfg: RunConfig
    make_env: EnvFactory
    ensemble: RewardEnsemble
    agent: Agent
    dataset: PreferenceDataset
    records: list[RoundRecord]
    out: Path | None = None
    kept: KeptPolicy = field(default_factory=KeptPolicy)
    """Continuous training's kept policy (`run.kept_policy`), saved with each checkpoint."""

    @classmethod
    def create(cls, cfg: RunConfig, out: Path | None = None, *, check: bool = False) -> "Run":
        """A fresh run with groupwise's own PPO on `cfg.loop.env`, writing into `out`
        (``config.json`` now; TensorBoard logs under ``tb/`` when PPO asks for them).

        Raises:
            ConfigMismatchError: `check` and `out` holds a ``config.json`` of another
                configuration (resuming must use the same options).
            ValueError: unknown env.
        """
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
            path = out / CONFIG_FILE
            if check and path.exists() and RunConfig.load(path) != cfg:
                raise ConfigMismatchError(
                    f"{path} was written by a different configuration; "
                    "use the same options to resume or another --out"
                )
            cfg.save(path)
        name = cfg.loop.env
        make_env(name).close()  # fail early, with the registry's message, on an unknown env
        make: EnvFactory = lambda: make_env(name)  # noqa: E731
        ensemble = RewardEnsemble.for_env(make, cfg.reward, init_rng(cfg.loop.seed))
        agent = PPOAgent(
            make,
            cfg.ppo,
            seed=cfg.loop.seed,
            reward_fn=ensemble.mean_reward,
            log_dir=None if out is None else out / TENSORBOARD_DIR,
        )
        return cls.of(cfg, make, ensemble, agent, out)

    @classmethod
    def of(
        cls,
        cfg: RunConfig,
        make: EnvFactory,
        ensemble: RewardEnsemble,
        agent: Agent,
        out: Path | None = None,
    ) -> "Run":
        """A fresh run over given parts (no feedback yet)."""
        dataset = PreferenceDataset.empty(
            cfg.loop.fragment_length, ensemble.obs_dim, ensemble.act_dim
        )
        return cls(cfg, make, ensemble, agent, dataset, [], out)

    @property
    def next_round(self) -> int:
        """The index of the round to run next."""
        return len(self.records)

    @property
    def ppo(self) -> PPOAgent:
        """The agent as groupwise's own PPO (checkpoints and pre-training need it)."""
        if not isinstance(self.agent, PPOAgent):
            raise TypeError("checkpoints and pre-training need groupwise's own PPOAgent")
        return self.agent

    @property
    def directory(self) -> Path:
        if self.out is None:
            raise ValueError("this run has no directory")
        return self.out

    def restore(self, after: int | None = None) -> bool:
        """Load the checkpoint written after round `after` (the latest when None; none,
        leaving the run fresh, for −1). False when there was none to load.

        Raises:
            FileNotFoundError: round `after`'s checkpoint is missing.
        """
        if after is not None and after < 0:
            return False
        if after is None:
            found = latest_checkpoint(self.directory)
            if found is None:
                return False
            directory, state = found
        else:
            directory = checkpoint_dir(self.directory, after)
            state = _read_state(directory)
        self.ppo.load(directory)
        self.ensemble.load_state(directory / REWARD_FILE)
        self.kept.load(directory)
        self.dataset = PreferenceDataset.load(directory / DATASET_FILE)
        self.records = [read_record(row) for row in state["records"]]
        log.info("%s restored after round %d", self.directory, state["round"])
        return True

    def commit(self) -> Path:
        """Write the checkpoint of the last round (atomically) and ``rounds.csv``."""
        out = self.directory

        def files(directory: Path) -> None:
            self.ppo.save(directory)
            self.ensemble.save(directory / REWARD_FILE)
            self.kept.save(directory)
            self.dataset.save(directory / DATASET_FILE)

        state = {
            "round": self.next_round - 1,
            "records": [dataclasses.asdict(r) for r in self.records],
        }
        path = write_checkpoint(out, self.next_round - 1, state, files)
        write_records(out / RESULTS_FILE, self.records)
        return path

    def save_mid_round(self, round_index: int) -> Path:
        """Write the policy and the reward ensemble as they are in the middle of round
        `round_index` (continuous training) into ``checkpoints/live``, atomically; the
        dataset is not saved: the round's judgements are the database's."""
        out = self.directory
        final = out / CHECKPOINTS / MID_ROUND_DIR
        tmp = final.with_name(final.name + ".tmp")
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
        self.save_policy(tmp)
        self.kept.save(tmp)
        state = {"round": round_index, "env_steps": self.agent.num_timesteps}
        (tmp / STATE_FILE).write_text(json.dumps(state))
        shutil.rmtree(final, ignore_errors=True)
        os.replace(tmp, final)
        return final

    def save_policy(self, directory: Path) -> None:
        """Write the policy and the reward ensemble as they are now into `directory` (a
        mid-round checkpoint's part; a snapshot another process samples the next round from)."""
        self.ppo.save(directory)
        self.ensemble.save(directory / REWARD_FILE)

    def load_policy(self, directory: Path) -> None:
        """Load what `save_policy` wrote."""
        self.ppo.load(directory)
        self.ensemble.load_state(directory / REWARD_FILE)

    def restore_mid_round(self, round_index: int) -> bool:
        """Load the mid-round checkpoint of round `round_index` over the restored run (policy and
        reward ensemble); False when there is none of that round."""
        directory = self.directory / CHECKPOINTS / MID_ROUND_DIR
        try:
            state = _read_state(directory)
        except FileNotFoundError:
            return False
        if state.get("round") != round_index:
            return False
        self.load_policy(directory)
        self.kept.load(directory)
        log.info(
            "%s resumed round %d at %d PPO steps", self.directory, round_index, state["env_steps"]
        )
        return True

    def drop_mid_round(self) -> None:
        """Remove the mid-round checkpoint (its round ended and was committed)."""
        shutil.rmtree(self.directory / CHECKPOINTS / MID_ROUND_DIR, ignore_errors=True)

    def close(self) -> None:
        """Release the agent's envs and loggers."""
        close = getattr(self.agent, "close", None)
        if callable(close):
            close()

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _read_state(directory: Path) -> dict[str, Any]:
    path = directory / STATE_FILE
    if not path.is_file():
        raise FileNotFoundError(f"no checkpoint in {directory}")
    state: dict[str, Any] = json.loads(path.read_text())
    return state
