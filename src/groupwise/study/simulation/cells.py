"""Study cells on disk: where a cell lives, when it is finished, and what it recorded.

Layout of a study directory::

    OUT/study.json                            the profile and every cell ever planned here
    OUT/cells/{env}/{dm}/seed-{k}/            one `run_session` directory per cell
    OUT/{ablation}/{env}/{dm}/seed-{k}/       an ablation's cells (`ablations.ABLATIONS`:
                                              capped, pairs2x, no-reward-norm)
    OUT/.../seed-{k}/done.json                written once the cell has finished

A cell directory without ``done.json`` is unfinished: rerunning the study resumes it from its
last round checkpoint.
"""

import csv
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from groupwise.study.simulation.ablations import ABLATIONS
from groupwise.types import FloatArray, IntArray

Condition = str
"""The main study (`MAIN`) or the name of an ablation (a key of `ABLATIONS`)."""

MAIN: Condition = "cells"
CONDITIONS: tuple[Condition, ...] = (MAIN, *ABLATIONS)
"""Every condition, each one directory of a study; the main study first."""
DONE_FILE = "done.json"
STUDY_FILE = "study.json"
ROUNDS_FILE = "rounds.csv"
CONFIG_FILE = "config.json"


@dataclass(frozen=True, order=True)
class Cell:
    """One independent run of the study: an env, a decision-maker and a seed."""

    env: str
    dm: str
    seed: int
    condition: Condition = MAIN
    """`MAIN`, or the ablation the cell runs (its directory and its key in ``study.json``)."""

    def __post_init__(self) -> None:
        if self.condition not in CONDITIONS:
            raise ValueError(
                f"unknown study condition {self.condition!r}; choose from {', '.join(CONDITIONS)}"
            )

    @property
    def ablation(self) -> str | None:
        """The ablation's name, None for a cell of the main study."""
        return None if self.condition == MAIN else self.condition

    @property
    def label(self) -> str:
        """Human-readable name for log lines, e.g. ``GridWorld/pairwise/seed-0 (capped)``."""
        suffix = f" ({self.ablation})" if self.ablation else ""
        return f"{self.env}/{self.dm}/seed-{self.seed}{suffix}"

    def directory(self, root: Path) -> Path:
        return root / self.condition / env_directory(self.env) / self.dm / f"seed-{self.seed}"

    def to_json(self) -> dict[str, Any]:
        return {"env": self.env, "dm": self.dm, "seed": self.seed, "condition": self.condition}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "Cell":
        return cls(data["env"], data["dm"], int(data["seed"]), data.get("condition", MAIN))


ENV_SEPARATOR = "--"
"""Stands for the ``/`` of a namespaced Gymnasium id (``dm_control/walker-walk-v0``) in a
cell's directory name, which must be one path component."""


def env_directory(env: str) -> str:
    """The directory name of `env`'s cells: ``dm_control--walker-walk-v0`` for
    ``dm_control/walker-walk-v0``; a plain name as it is."""
    return env.replace("/", ENV_SEPARATOR)


def env_of_directory(name: str) -> str:
    """The env whose cells a directory named `name` holds (`env_directory` undone)."""
    return name.replace(ENV_SEPARATOR, "/")


def is_done(directory: Path) -> bool:
    return (directory / DONE_FILE).is_file()


def mark_done(directory: Path, summary: dict[str, Any]) -> None:
    """Write ``done.json`` atomically (a cell killed while writing it is simply rerun)."""
    tmp = directory / (DONE_FILE + ".tmp")
    tmp.write_text(json.dumps(summary, indent=1) + "\n")
    os.replace(tmp, directory / DONE_FILE)


@dataclass(frozen=True)
class CellRecord:
    """What one cell wrote so far: its ``rounds.csv`` as arrays of shape (rows,)."""

    cell: Cell
    complete: bool
    """``done.json`` exists."""
    planned_rows: int
    """Rows a finished cell has: the rounds plus one when it trains on the frozen reward."""
    comparisons: int
    """Total comparisons the cell's config asks for."""
    round: IntArray
    env_steps: IntArray
    true_return: FloatArray
    """`RoundRecord.true_return_mean` after each row."""
    pairs: IntArray
    pairs_total: IntArray
    label_error_rate_total: FloatArray
    round_comparisons: IntArray
    """`RoundRecord.comparisons` per row."""
    judgements: FloatArray
    queries_asked: FloatArray
    """`RoundRecord.queries_asked` per row, and the other diagnostics below (nan in cells
    written before they were recorded)."""
    queries_unused: FloatArray
    queries_skipped: FloatArray
    candidates: FloatArray
    return_sd_over_noise: FloatArray

    @property
    def rows(self) -> int:
        return len(self.round)

    @property
    def final_return(self) -> float:
        return float(self.true_return[-1]) if self.rows else math.nan

    @property
    def final_pairs(self) -> int:
        return int(self.pairs_total[-1]) if self.rows else 0

    @property
    def final_error_rate(self) -> float:
        return float(self.label_error_rate_total[-1]) if self.rows else math.nan

    def _feedback_mean(self, values: FloatArray) -> float:
        """Mean over the rows that asked for feedback (nan when none or unrecorded)."""
        asked = self.round_comparisons > 0
        chosen = values[asked]
        return float(np.nanmean(chosen)) if np.isfinite(chosen).any() else math.nan

    @property
    def mean_asked(self) -> float:
        return self._feedback_mean(self.queries_asked)

    @property
    def mean_unused(self) -> float:
        return self._feedback_mean(self.queries_unused)

    @property
    def mean_skipped(self) -> float:
        return self._feedback_mean(self.queries_skipped)

    @property
    def mean_judged(self) -> float:
        return self._feedback_mean(self.judgements)

    @property
    def mean_candidates(self) -> float:
        return self._feedback_mean(self.candidates)

    @property
    def mean_signal(self) -> float:
        """Mean pool return sd ÷ noise sd over the feedback rounds."""
        return self._feedback_mean(self.return_sd_over_noise)


def read_cell(cell: Cell, root: Path) -> CellRecord | None:
    """The record of `cell` under study directory `root`, or None when it never started.

    A cell that wrote its config but no round yet gives a record with zero rows.

    Raises:
        ValueError: a ``rounds.csv`` or ``config.json`` that cannot be parsed.
    """
    directory = cell.directory(root)
    config_path = directory / CONFIG_FILE
    if not config_path.is_file():
        return None
    loop = json.loads(config_path.read_text()).get("loop", {})
    planned = int(loop.get("rounds", 0)) + (1 if int(loop.get("final_steps", 0)) > 0 else 0)
    rows: list[dict[str, str]] = []
    if (directory / ROUNDS_FILE).is_file():
        with (directory / ROUNDS_FILE).open(newline="") as handle:
            rows = list(csv.DictReader(handle))

    def column(name: str, kind: type) -> np.ndarray:
        try:
            return np.array([kind(float(row[name])) for row in rows], dtype=kind)
        except (KeyError, ValueError) as error:
            raise ValueError(f"{directory / ROUNDS_FILE}: bad column {name!r}: {error}") from None

    def optional(name: str) -> np.ndarray:
        if rows and name not in rows[0]:
            return np.full(len(rows), np.nan)
        return column(name, float)

    return CellRecord(
        cell=cell,
        complete=is_done(directory),
        planned_rows=planned,
        comparisons=int(loop.get("comparisons", 0)),
        round=column("round", int),
        env_steps=column("env_steps", int),
        true_return=column("true_return_mean", float),
        pairs=column("pairs", int),
        pairs_total=column("pairs_total", int),
        label_error_rate_total=column("label_error_rate_total", float),
        round_comparisons=column("comparisons", int),
        judgements=column("judgements", float),
        queries_asked=optional("queries_asked"),
        queries_unused=optional("queries_unused"),
        queries_skipped=optional("queries_skipped"),
        candidates=optional("candidates"),
        return_sd_over_noise=optional("return_sd_over_noise"),
    )


def discover_cells(root: Path) -> list[Cell]:
    """Every cell that has a directory under `root`, sorted."""
    found = []
    for condition in CONDITIONS:
        for seed_dir in (root / condition).glob("*/*/seed-*"):
            env, dm = env_of_directory(seed_dir.parent.parent.name), seed_dir.parent.name
            try:
                seed = int(seed_dir.name.removeprefix("seed-"))
            except ValueError:
                continue
            found.append(Cell(env, dm, seed, condition))
    return sorted(found)


def read_plan(root: Path) -> dict[str, Any] | None:
    """The contents of ``study.json``, or None when the directory has none."""
    path = root / STUDY_FILE
    return json.loads(path.read_text()) if path.is_file() else None


def planned_cells(root: Path) -> list[Cell]:
    plan = read_plan(root)
    return sorted(Cell.from_json(c) for c in plan["cells"]) if plan else []


def write_plan(root: Path, profile: str, cells: list[Cell]) -> None:
    """Record `profile` and the union of `cells` with the cells planned before."""
    known = set(planned_cells(root)) | set(cells)
    data = {"profile": profile, "cells": [c.to_json() for c in sorted(known)]}
    tmp = root / (STUDY_FILE + ".tmp")
    tmp.write_text(json.dumps(data, indent=1) + "\n")
    os.replace(tmp, root / STUDY_FILE)
