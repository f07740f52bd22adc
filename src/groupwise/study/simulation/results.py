"""A study directory read into arrays: final scores ``{dm: array[runs, envs]}`` and curves.

Only finished cells (``done.json``) count as final results; unfinished ones still add to the
training curves as far as they got, and are listed as such.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from groupwise.study.simulation.ablations import ABLATIONS
from groupwise.study.simulation.cells import (
    MAIN,
    Cell,
    CellRecord,
    Condition,
    discover_cells,
    read_cell,
    read_plan,
)
from groupwise.types import FloatArray

ENV_ORDER = ("Hopper", "HalfCheetah", "Walker2d", "Reacher", "MountainCarContinuous", "GridWorld")
"""The paper's table order; other envs follow alphabetically."""


@dataclass(frozen=True)
class Grid:
    """Final values of one condition laid out as ``{dm: array[runs, envs]}``."""

    dms: tuple[str, ...]
    envs: tuple[str, ...]
    seeds: tuple[int, ...]
    """Run index → seed; a run a DM or env lacks is NaN."""
    values: dict[str, FloatArray]
    """``{dm: array[len(seeds), len(envs)]}``."""


@dataclass(frozen=True)
class Curves:
    """Per-row true returns of the runs of one (env, DM)."""

    steps: FloatArray
    """(points,) mean env steps after each row, over the runs that reached it."""
    returns: FloatArray
    """(runs, points); NaN after the last row a run has written."""


@dataclass(frozen=True)
class StudyResults:
    root: Path
    profile: str | None
    planned: tuple[Cell, ...]
    """Cells ``study.json`` names (empty for a directory without one)."""
    records: dict[Cell, CellRecord]
    """Every cell that has started."""
    sources: tuple[Path, ...] = ()
    """The study directories merged into this one (`merge_results`); empty for one study."""

    def finished(self, condition: Condition) -> list[CellRecord]:
        return [
            r for c, r in sorted(self.records.items()) if r.complete and c.condition == condition
        ]

    def unfinished(self) -> list[CellRecord]:
        return [r for _, r in sorted(self.records.items()) if not r.complete]

    def not_started(self) -> list[Cell]:
        return [c for c in self.planned if c not in self.records]

    def ablations(self) -> tuple[str, ...]:
        """The ablations with at least one finished cell, in `ABLATIONS` order."""
        done = {c.condition for c, r in self.records.items() if r.complete}
        return tuple(name for name in ABLATIONS if name in done)

    def envs(self, condition: Condition) -> tuple[str, ...]:
        return _env_order({c.env for c in self.records if c.condition == condition})

    def dms(self, condition: Condition) -> tuple[str, ...]:
        return dm_order({c.dm for c in self.records if c.condition == condition})

    def grid(self, condition: Condition, field: str = "final_return") -> Grid:
        """A property of the finished cells (`CellRecord.final_return`, `final_pairs`, …)."""
        records = self.finished(condition)
        dms = dm_order({r.cell.dm for r in records})
        envs = _env_order({r.cell.env for r in records})
        seeds = tuple(sorted({r.cell.seed for r in records}))
        values = {dm: np.full((len(seeds), len(envs)), np.nan) for dm in dms}
        for r in records:
            row, col = seeds.index(r.cell.seed), envs.index(r.cell.env)
            values[r.cell.dm][row, col] = float(getattr(r, field))
        return Grid(dms, envs, seeds, values)

    def capped_grid(self) -> tuple[Grid, tuple[str, ...]]:
        """Final returns of the capped ablation, and the DMs whose uncapped cells stand in.

        A DM without capped cells whose every finished uncapped cell kept at most one pair
        per comparison in every round (the pairwise DM) is unchanged by the cap, so its
        uncapped cells are used. Empty when no capped cell has finished.
        """
        capped = self.finished("capped")
        if not capped:
            return Grid((), (), (), {}), ()
        envs = _env_order({r.cell.env for r in capped})
        have = {(r.cell.env, r.cell.dm) for r in capped}
        stand_ins: set[str] = set()
        records = list(capped)
        uncapped = self.finished(MAIN)
        for env in envs:  # per env: a merged study may have capped cells of a DM elsewhere
            for dm in self.dms(MAIN):
                if (env, dm) in have:
                    continue
                main = [r for r in uncapped if r.cell.dm == dm and r.cell.env == env]
                if main and all(_within_cap(r) for r in main):
                    stand_ins.add(dm)
                    records += main
        dms = dm_order({r.cell.dm for r in records})
        seeds = tuple(sorted({r.cell.seed for r in records}))
        values = {dm: np.full((len(seeds), len(envs)), np.nan) for dm in dms}
        for r in records:
            values[r.cell.dm][seeds.index(r.cell.seed), envs.index(r.cell.env)] = r.final_return
        return Grid(dms, envs, seeds, values), tuple(dm_order(stand_ins))

    def curves(self, condition: Condition, env: str, dm: str) -> Curves | None:
        """Training curve data of (env, dm): every started run that wrote a row."""
        runs = [
            r
            for c, r in sorted(self.records.items())
            if c.condition == condition and c.env == env and c.dm == dm and r.rows
        ]
        if not runs:
            return None
        points = max(r.rows for r in runs)
        returns = np.full((len(runs), points), np.nan)
        steps = np.full((len(runs), points), np.nan)
        for i, r in enumerate(runs):
            returns[i, : r.rows] = r.true_return
            steps[i, : r.rows] = r.env_steps
        return Curves(np.nanmean(steps, axis=0), returns)


def merge_results(parts: Sequence[StudyResults], root: Path) -> StudyResults:
    """Several study directories read as one study at `root` (e.g. ``session`` and
    ``mujoco``, for the paper's table on all six envs).

    Raises:
        ValueError: no parts, or one cell (env, DM, seed, condition) in two of them.
    """
    if not parts:
        raise ValueError("nothing to merge")
    records: dict[Cell, CellRecord] = {}
    where: dict[Cell, Path] = {}
    for part in parts:
        for cell, record in part.records.items():
            if cell in records:
                raise ValueError(f"{cell.label} is in both {where[cell]} and {part.root}")
            records[cell], where[cell] = record, part.root
    planned = tuple(sorted({c for part in parts for c in part.planned}))
    profiles = " + ".join(dict.fromkeys(p.profile or "unknown" for p in parts))
    return StudyResults(root, profiles, planned, records, tuple(p.root for p in parts))


def load_results(root: Path) -> StudyResults:
    """Read every cell under study directory `root`.

    Raises:
        ValueError: a cell's files cannot be parsed.
    """
    plan = read_plan(root)
    planned = tuple(sorted(Cell.from_json(c) for c in plan["cells"])) if plan else ()
    records = {}
    for cell in sorted(set(discover_cells(root)) | set(planned)):
        record = read_cell(cell, root)
        if record is not None:
            records[cell] = record
    return StudyResults(root, plan["profile"] if plan else None, planned, records)


def dm_order(names: set[str]) -> tuple[str, ...]:
    """The decision-makers in registry order, unknown ones after them alphabetically."""
    from groupwise.teachers import DECISION_MAKERS

    known = [name for name in DECISION_MAKERS if name in names]
    return (*known, *sorted(names - set(known)))


def _env_order(names: set[str]) -> tuple[str, ...]:
    known = [name for name in ENV_ORDER if name in names]
    return (*known, *sorted(names - set(known)))


def _within_cap(record: CellRecord) -> bool:
    return bool(np.all(record.pairs <= record.round_comparisons))
