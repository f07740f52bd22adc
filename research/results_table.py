"""Results as data: the case-study run folders as one tidy CSV, and the README tables from it.

    python research/results_table.py collect docs/results/case-studies/walker
    python research/results_table.py render docs/results
    python research/results_table.py check docs/results          # `make lint` runs this
    python research/results_table.py figure RUNS.csv PNG [--colour dm]

`collect FOLDER` finds every run folder under FOLDER (a directory with a `config.json` and a
`case-study.csv`, as `groupwise case-study --out` writes it) and writes FOLDER/runs.csv:
one row per run and round. Each row holds the run's setup (folder, setup = the run's parent
relative to FOLDER, run, target, env, dm, label, seed), the round, every column of the run's
`case-study.csv`, every column of its `rounds.csv` prefixed `loop.`, the take-away
evaluation of that round (`takeaway.score`, `takeaway.return`), every scalar of its
`summary.json` prefixed `summary.` (lists joined with ";"), and the `config.json` values
that differ between the runs of FOLDER prefixed `config.`; the values all of them share go
to FOLDER/runs-config.json. Values are copied as written, never re-formatted.

`render` rewrites every table between `<!-- table:KIND key=value ... -->` and
`<!-- /table -->` in the Markdown files under the given paths from the CSV the marker
names (`csv=`, default runs.csv beside the file); `check` renders the same and exits 1,
printing a diff, when a file's table differs. KIND is `runs` (a row per run: comparisons,
preference pairs, tied pairs, label error on the untied ones, target score after each
round, final success and stretch, wall time), `summary` (a row per target and label:
successful seeds after the last round and as take-away agent, stretch, comparisons, pairs,
the pools' target-score spread and best in rounds 0–2), `setups` (a row per selection
written in the marker, `setups_table`) or `matrix` (targets × selections, `matrix_table`).
For `runs` and `summary`, any other key=value filters the rows on that CSV column
(`seed=5|6|7`, `label="groupwise · 8 pool variants"`; the runs are ordered by the filters'
lists, in the order the filters are written). Options: `csv=PATH|PATH` (the runs of
several tables); `name="{dm}, {ppo} PPO"` names a run by its columns (`{column:format
spec}`; by default `{label}`), `name:SETUP=...` the runs of one setup; `scores=rounds`
heads the score column "target score after rounds 0 … N"; `pool=no` drops the summary's
pool columns; `title="..."` names the label column ("DM" by default).
"""

import argparse
import csv
import difflib
import json
import re
import shlex
import sys
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

SEED_SUCCESS = 0.6
"""A seed succeeds when this share of its final greedy episodes (3 of 5) reach the threshold
(docs/case-studies.md)."""

SETUP_COLUMNS = ("folder", "setup", "run", "target", "env", "dm", "label", "ppo", "seed", "round")
SKIPPED_SUMMARY = {"target.description", "filmed.why", "takeaway.why", "takeaway.verdicts"}
"""Prose repeated on every row, and the teacher's verdicts between rounds (a list of
records; the round it chose is `summary.takeaway.round`)."""
SHARED_CONFIG = "runs-config.json"
"""Beside runs.csv: the `config.json` values every run of the folder shares."""
PER_ROUND_SUMMARY = {"takeaway.rounds", "takeaway.scores", "takeaway.returns"}
"""Lists over the rounds: on each round's row as `takeaway.score` and `takeaway.return`."""

MARKER = re.compile(
    r"<!-- table:(?P<kind>\w+)(?P<args>[^>]*?)\s*-->\n(?P<body>.*?)<!-- /table -->", re.S
)


class TableError(ValueError):
    """A run folder, CSV or marker that cannot be read; the message says which."""


# --- collect -------------------------------------------------------------------------------


def run_folders(folder: Path) -> list[Path]:
    """Every run folder under `folder` (itself included), in path order."""
    found = {p.parent for p in folder.rglob("case-study.csv")}
    return sorted(run for run in found if (run / "config.json").is_file())


def _flatten(value: Any, prefix: str, out: dict[str, str]) -> None:
    """`value`'s scalars into `out` under dotted keys; lists of scalars joined with ";"."""
    if isinstance(value, dict):
        for key, item in value.items():
            _flatten(item, f"{prefix}.{key}" if prefix else str(key), out)
    elif isinstance(value, list):
        if all(not isinstance(v, dict | list) for v in value):
            out[prefix] = ";".join(_scalar(v) for v in value)
    else:
        out[prefix] = _scalar(value)


def _scalar(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value).lower()
    return repr(value) if isinstance(value, float) else str(value)


def label(config: dict[str, Any], dm: str) -> str:
    """The run's decision-maker with the setup it ran with, as the READMEs name it
    ("groupwise · 8 pool variants · pre-training 100,000"): the rule the tables have used
    since issue 20, read from `config.json` so it holds for settings the code no longer has."""
    loop, training, reward = config["loop"], config.get("training", {}), config.get("reward", {})
    parts = [dm]
    if size := loop.get("pool_size"):
        parts.append(f"pools of {size:,}")
    if variants := loop.get("pool_variants", 0):
        greedy = " of the greedy policy" if loop.get("pool_variants_greedy") else ""
        steps = loop.get("pool_lookahead", 0)
        ahead = f" after a {steps:,}-step lookahead" if steps else ""
        parts.append(f"{variants} pool variants{greedy}{ahead}")
    if loop.get("adopt_variants"):
        parts.append("adopted")
    if pretrain := training.get("pretrain_steps", 0):
        parts.append(f"pre-training {pretrain:,}")
    if loop.get("suggestion_rank", "variance") != "variance":
        parts.append(f"{loop['suggestion_rank']} suggestions")
    if bonus := reward.get("exploration_bonus", 0):
        parts.append(f"reward bonus {bonus:g}")
    if pessimism := reward.get("pessimism", 0):
        parts.append(f"reward pessimism {pessimism:g}")
    if training.get("continue_from", "last") != "last":
        parts.append("training on from the preferred policy")
    return " · ".join(parts)


def ppo_preset(config: dict[str, Any]) -> str:
    """The name of the `PPO_PRESETS` entry the run's PPO settings equal, else "custom".
    Imported here: `render` and `check` read CSVs alone and need no groupwise."""
    from groupwise.recipes import PPO_PRESETS

    ppo = config.get("ppo", {})
    for name, preset in PPO_PRESETS.items():
        fields = {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(preset).items()}
        if all(ppo.get(k) == v for k, v in fields.items() if k in ppo):
            return name
    return "custom"


def _csv_rows(path: Path) -> list[dict[str, str]]:
    if not path.is_file():
        return []
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def _read_json(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise TableError(f"{path}: cannot read ({error})") from error
    if not isinstance(data, dict):
        raise TableError(f"{path}: not a JSON object")
    return data


def run_rows(run: Path, folder: Path) -> tuple[list[dict[str, str]], dict[str, str]]:
    """The rows of one run folder (config columns not yet added) and its flat config."""
    config = _read_json(run / "config.json")
    summary = _read_json(run / "summary.json") if (run / "summary.json").is_file() else {}
    flat_config: dict[str, str] = {}
    _flatten(config, "", flat_config)
    flat_summary: dict[str, str] = {}
    _flatten(summary, "", flat_summary)
    takeaway = summary.get("takeaway", {})
    takeaway_config: dict[str, str] = {}
    if (run / "takeaway.json").is_file():
        _flatten(_read_json(run / "takeaway.json").get("config", {}), "config", takeaway_config)
    by_round = {
        int(r): (_scalar(s), _scalar(g))
        for r, s, g in zip(
            takeaway.get("rounds", []),
            takeaway.get("scores", []),
            takeaway.get("returns", []),
            strict=True,
        )
    }
    loop = config["loop"]  # runs written before issue 38 name the decision-maker "oracle"
    dm = summary.get("decision_maker") or loop.get("decision_maker", loop.get("oracle", ""))
    setup = run.parent.relative_to(folder).as_posix() if run != folder else ""
    base = {
        "folder": folder.name,
        "setup": "" if setup == "." else setup,
        "run": run.name if run != folder else ".",
        "target": summary.get("target", {}).get("name", config["loop"]["env"]),
        "env": config["loop"]["env"],
        "dm": dm,
        "label": label(config, dm),
        "ppo": ppo_preset(config),
        "seed": str(config["loop"]["seed"]),
    }
    loop_rows = {row["round"]: row for row in _csv_rows(run / "rounds.csv")}
    rows = []
    for study_row in _csv_rows(run / "case-study.csv"):
        row = dict(base, round=study_row["round"])
        row.update((k, v) for k, v in study_row.items() if k != "round")
        loop_row = loop_rows.get(study_row["round"], {})
        row.update((f"loop.{k}", v) for k, v in loop_row.items() if k != "round")
        score, ret = by_round.get(int(study_row["round"]), ("", ""))
        row["takeaway.score"], row["takeaway.return"] = score, ret
        row.update(
            (f"summary.{k}", v)
            for k, v in flat_summary.items()
            if k not in SKIPPED_SUMMARY | PER_ROUND_SUMMARY
        )
        row.update((f"takeaway.{k}", v) for k, v in takeaway_config.items())
        rows.append(row)
    if not rows:
        raise TableError(f"{run}: case-study.csv has no rounds")
    return rows, flat_config


def collect(folder: Path) -> tuple[list[dict[str, str]], dict[str, Any]]:
    """The tidy rows of every run folder under `folder` (module docstring), and the
    `config.json` values all of them share (nested as in `config.json`).

    Raises:
        TableError: no run folder under `folder`, or one that cannot be read.
    """
    runs = run_folders(folder)
    if not runs:
        raise TableError(f"{folder}: no run folder (config.json beside case-study.csv)")
    read = [run_rows(run, folder) for run in runs]
    keys = list(dict.fromkeys(k for _, flat in read for k in flat))
    varying = [k for k in keys if len({flat.get(k) for _, flat in read}) > 1 and k != "loop.seed"]
    rows = []
    for run_of_rows, flat in read:
        for row in run_of_rows:
            row.update((f"config.{k}", flat.get(k, "")) for k in varying)
            rows.append(row)
    return rows, _without(_read_json(runs[0] / "config.json"), {*varying, "loop.seed"})


def _without(config: dict[str, Any], keys: set[str], prefix: str = "") -> dict[str, Any]:
    """`config` less the dotted `keys` (and any section left empty)."""
    kept: dict[str, Any] = {}
    for key, value in config.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, dict):
            if inner := _without(value, keys, f"{dotted}."):
                kept[key] = inner
        elif dotted not in keys:
            kept[key] = value
    return kept


def write_csv(rows: Sequence[dict[str, str]], path: Path) -> Path:
    """`rows` as CSV, the setup columns first, the others in order of first appearance."""
    columns = list(dict.fromkeys([*SETUP_COLUMNS, *(k for row in rows for k in row)]))
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, columns, restval="", lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return path


# --- render --------------------------------------------------------------------------------


@dataclass(frozen=True)
class Run:
    """One run's rows of the tidy table, in round order."""

    rows: tuple[dict[str, str], ...]
    name: str = ""
    """What the table calls the run's setup (`name=` of the marker; the `label` column)."""

    @property
    def last(self) -> dict[str, str]:
        return self.rows[-1]

    def get(self, column: str) -> str:
        return self.name if column == "name" else self.last.get(column, "")


def read_runs(path: Path) -> list[Run]:
    """The runs of a tidy CSV, in the order of their first row."""
    if not path.is_file():
        raise TableError(f"{path}: no such table (run `results_table.py collect` first)")
    grouped: dict[tuple[str, str], list[dict[str, str]]] = {}
    for row in _csv_rows(path):
        grouped.setdefault((row["setup"], row["run"]), []).append(row)
    return [Run(tuple(sorted(rows, key=lambda r: int(r["round"])))) for rows in grouped.values()]


FIELD = re.compile(r"\{(?P<column>[^{}:]+)(?::(?P<spec>[^{}]*))?\}")


def _typed(text: str) -> int | float | str:
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def named(run: Run, template: str) -> Run:
    """`run` named by `template`: `{column}` or `{column:format spec}` of its last row."""

    def field(match: re.Match[str]) -> str:
        if match["column"] != "name" and match["column"] not in run.last:
            raise TableError(f"name={template!r}: no column {match['column']!r}")
        return format(_typed(run.get(match["column"])), match["spec"] or "")

    return Run(run.rows, FIELD.sub(field, template))


def select(runs: Iterable[Run], filters: dict[str, list[str]]) -> list[Run]:
    """The runs whose columns match every filter, ordered by the filters' value lists."""
    kept = [run for run in runs if all(run.get(k) in values for k, values in filters.items())]
    return sorted(kept, key=lambda run: [values.index(run.get(k)) for k, values in filters.items()])


def _number(text: str) -> float:
    return float(text) if text not in ("", "nan") else float("nan")


def _span(values: Iterable[int]) -> str:
    low, high = min(values := list(values)), max(values)
    return f"{low:,}" if low == high else f"{low:,}–{high:,}"


def runs_table(runs: Sequence[Run], options: dict[str, str]) -> list[str]:
    """A row per run (module docstring)."""
    last_round = max((len(run.rows) for run in runs), default=1) - 1
    scores = (
        f"target score after rounds 0 … {last_round}"
        if options.get("scores") == "rounds"
        else "target score after each round"
    )
    lines = [
        f"| target | {options.get('title', 'DM')} | seed | comparisons | preference pairs "
        f"| tied pairs | label error (untied) | {scores} | success | stretch | wall |",
        "|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|",
    ]
    for run in runs:
        last = run.last
        episodes = len(last["summary.final.scores"].split(";"))
        ties, error = "–", "–"  # no pairs: nothing tied, nothing labelled
        if int(last["pairs_total"]):
            ties = f"{_number(last['tied_share_total']):.2f}"
            error = f"{_number(last['label_error_untied_total']):.2f}"
        per_round = ", ".join(f"{_number(r['target_score_mean']):.2f}" for r in run.rows)
        success = round(_number(last["summary.final.success_rate"]) * episodes)
        stretch = round(_number(last["summary.final.stretch_rate"]) * episodes)
        lines.append(
            f"| {last['target']} | {run.name} | {last['seed']} "
            f"| {int(last['comparisons_total'])} | {int(last['pairs_total']):,} | {ties} | {error} "
            f"| {per_round} | {success}/{episodes} | {stretch}/{episodes} "
            f"| {_number(last['wall_s']):.0f} s |"
        )
    return lines


def _pool_means(runs: Sequence[Run], column: str) -> str:
    """Per round 0–2 the mean over the runs of `column` ("–" where no run has it)."""
    means = []
    for r in range(3):
        rows = [run.rows[r] for run in runs if r < len(run.rows)]
        values = [_number(row[column]) for row in rows if row.get(column)]
        means.append(f"{sum(values) / len(values):.2f}" if values else "–")
    return " / ".join(means)


FINAL = "summary.final.success_rate"


def summary_table(runs: Sequence[Run], options: dict[str, str]) -> list[str]:
    """A row per target and label (module docstring), in order of first appearance."""
    pool = options.get("pool", "yes") != "no"
    head = (
        f"| target | {options.get('title', 'DM')} | seeds | successful seeds, last round "
        "| as take-away agent | stretch | comparisons | preference pairs |"
    )
    rule = "|---|---|---:|---:|---:|---:|---:|---:|"
    if pool:
        head += " pool sd, rounds 0–2 | pool max, rounds 0–2 |"
        rule += "---|---|"
    cells: dict[tuple[str, str], list[Run]] = {}
    for run in runs:
        cells.setdefault((run.get("target"), run.name), []).append(run)
    lines = [head, rule]
    for (target, dm), group in cells.items():
        n = len(group)

        def seeds(column: str, group: list[Run] = group) -> int:
            return sum(_number(run.get(column)) >= SEED_SUCCESS for run in group)

        kept = sum(
            _number(run.get("summary.takeaway.success_rate") or run.get(FINAL)) >= SEED_SUCCESS
            for run in group
        )
        line = (
            f"| {target} | {dm} | {n} | **{seeds(FINAL)}/{n}** | {kept}/{n} "
            f"| {seeds('summary.final.stretch_rate')}/{n} "
            f"| {_span(int(run.get('summary.comparisons')) for run in group)} "
            f"| {_span(int(run.get('summary.preference_pairs')) for run in group)} |"
        )
        if pool:
            sd, best = _pool_means(group, "pool_score_sd"), _pool_means(group, "pool_score_max")
            line += f" {sd} | {best} |"
        lines.append(line)
    return lines


def _seed_span(runs: Sequence[Run]) -> str:
    seeds = sorted(int(run.get("seed")) for run in runs)
    if seeds == list(range(seeds[0], seeds[-1] + 1)) and len(seeds) > 1:
        return f"{seeds[0]}–{seeds[-1]}"
    return ", ".join(map(str, seeds))


def _count(runs: Sequence[Run], column: str, fallback: str = "") -> str:
    won = sum(
        _number(run.get(column) or run.get(fallback or column)) >= SEED_SUCCESS for run in runs
    )
    return f"{won}/{len(runs)}"


SETUP_CELLS: dict[str, tuple[str, Callable[[Sequence[Run]], str]]] = {
    "seeds": ("---", _seed_span),
    "last": ("---:", lambda runs: _count(runs, FINAL)),
    "takeaway": ("---:", lambda runs: _count(runs, "summary.takeaway.success_rate", FINAL)),
    "stretch": ("---:", lambda runs: _count(runs, "summary.final.stretch_rate")),
    "scores": (
        "---",
        lambda runs: ", ".join(f"{_number(run.get('target_score_mean')):.2f}" for run in runs),
    ),
}
"""The cells of a `setups` row, each with its column's alignment: the seeds, the successful
seeds after the last round, as take-away agent, at the stretch, and every seed's target
score after the last round."""


def setups_table(args: str, rows: Sequence[str], base: Path) -> list[str]:
    """One row per setup: `args` holds `head="first|second|..."` (the header cells) and
    `cells="last|takeaway|..."` (`SETUP_CELLS`, after the setup's own text); each line of
    `rows` is "TEXT :: key=value ..." (filters, `csv=`, `bold=CELL|CELL`), its runs in seed
    order."""
    options, _ = _parse("setups", args, {"head", "cells", "csv"})
    cells = options.get("cells", "last|takeaway|stretch|scores").split("|")
    if unknown := [cell for cell in cells if cell not in SETUP_CELLS]:
        raise TableError(
            f"table:setups: unknown cell {unknown[0]!r} (one of {', '.join(SETUP_CELLS)})"
        )
    head = options.get("head", "|".join(["setup", *cells])).split("|")
    if len(head) != len(cells) + 1:
        raise TableError(f"table:setups: {len(head)} header cells for {len(cells) + 1} columns")
    lines = [
        "| " + " | ".join(cell.strip() for cell in head) + " |",
        "|---|" + "".join(f"{SETUP_CELLS[cell][0]}|" for cell in cells),
    ]
    for row in rows:
        text, sep, spec = row.partition(" :: ")
        if not sep:
            raise TableError(f"table:setups: {row!r} is not 'TEXT :: filters'")
        row_options, filters = _parse("setups", spec, {"csv", "bold"})
        tables = row_options.get("csv", options.get("csv", "runs.csv")).split("|")
        runs = select((run for table in tables for run in read_runs(base / table)), filters)
        if not runs:
            raise TableError(f"table:setups: no run matches {spec.strip()!r}")
        runs = sorted(runs, key=lambda run: int(run.get("seed")))
        bold = set(row_options.get("bold", "").split("|"))
        values = [SETUP_CELLS[cell][1](runs) for cell in cells]
        values = [f"**{v}**" if cell in bold else v for cell, v in zip(cells, values, strict=True)]
        lines.append("| " + " | ".join([text.strip(), *values]) + " |")
    return lines


def matrix_table(args: str, columns: Sequence[str], base: Path) -> list[str]:
    """Targets down, setups across: `args` holds `rows="target|target|..."` and the cell
    template `cell="{last} ({takeaway})"` (fields `last`, `takeaway`, `stretch`: successful
    seeds of the target's runs in the column, as in `SETUP_CELLS`); each line of `columns`
    is "HEADER :: key=value ..." (filters, `csv=`, `cell=` for this column, and
    `bold=target:field|...` to set a field in bold)."""
    options, _ = _parse("matrix", args, {"rows", "cell", "csv", "title"})
    targets = options.get("rows", "").split("|")
    if not columns or targets == [""]:
        raise TableError("table:matrix: needs rows=target|... and a line per column")
    header = [options.get("title", "target")]
    cells: list[list[str]] = [[target] for target in targets]
    for column in columns:
        text, sep, spec = column.partition(" :: ")
        if not sep:
            raise TableError(f"table:matrix: {column!r} is not 'HEADER :: filters'")
        column_options, filters = _parse("matrix", spec, {"csv", "cell", "bold"})
        tables = column_options.get("csv", options.get("csv", "runs.csv")).split("|")
        runs = select((run for table in tables for run in read_runs(base / table)), filters)
        template = column_options.get("cell", options.get("cell", "{last} ({takeaway})"))
        bold = set(column_options.get("bold", "").split("|"))
        header.append(text.strip())
        for row, target in zip(cells, targets, strict=True):
            mine = [run for run in runs if run.get("target") == target]
            if not mine:
                raise TableError(f"table:matrix: no {target} run matches {spec.strip()!r}")
            fields = {name: SETUP_CELLS[name][1](mine) for name in ("last", "takeaway", "stretch")}
            fields = {k: f"**{v}**" if f"{target}:{k}" in bold else v for k, v in fields.items()}
            row.append(template.format_map(fields))
    return [
        "| " + " | ".join(header) + " |",
        "|---|" + "---:|" * len(columns),
        *("| " + " | ".join(row) + " |" for row in cells),
    ]


KINDS = {"runs": runs_table, "summary": summary_table}
OPTIONS = {"csv", "scores", "pool", "title", "name"}


def _parse(
    kind: str, args: str, options_allowed: set[str]
) -> tuple[dict[str, str], dict[str, list[str]]]:
    """A marker's key=value words: the options among `options_allowed` (and `name:SETUP`),
    and the filters (every other key; a value's "|" separates alternatives)."""
    options: dict[str, str] = {}
    filters: dict[str, list[str]] = {}
    try:
        words = shlex.split(args)
    except ValueError as error:
        raise TableError(f"table:{kind}{args}: {error}") from error
    for arg in words:
        key, sep, value = arg.partition("=")
        if not sep:
            raise TableError(f"table:{kind}: {arg!r} is not key=value")
        if key in options_allowed or key.startswith("name:"):
            options[key] = value
        else:
            filters[key] = value.split("|")
    return options, filters


def render_table(kind: str, args: str, base: Path) -> list[str]:
    """The Markdown lines of one marker's table; `base` is the folder of the file holding it.

    Raises:
        TableError: an unknown kind or argument, or a selection without runs.
    """
    if kind in ("setups", "matrix"):
        first, *lines = args.split("\n")
        table = setups_table if kind == "setups" else matrix_table
        return table(first, [line for line in lines if line.strip()], base)
    if kind not in KINDS:
        raise TableError(
            f"unknown table kind {kind!r} (one of {', '.join([*KINDS, 'setups', 'matrix'])})"
        )
    options, filters = _parse(kind, args, OPTIONS)
    tables = options.get("csv", "runs.csv").split("|")

    def template(run: Run) -> str:
        return options.get(f"name:{run.get('setup')}", options.get("name", "{label}"))

    every = (run for table in tables for run in read_runs(base / table))
    runs = select((named(run, template(run)) for run in every), filters)
    if not runs:
        raise TableError(f"table:{kind}{args}: no run matches")
    return KINDS[kind](runs, options)


def rendered(text: str, base: Path) -> str:
    """`text` with every marked table rendered afresh."""

    def replace(match: re.Match[str]) -> str:
        lines = render_table(match["kind"], match["args"], base)
        head = match.group(0)[: match.start("body") - match.start()]
        return head + "\n".join(lines) + "\n<!-- /table -->"

    return MARKER.sub(replace, text)


def marked_files(paths: Sequence[Path]) -> Iterator[Path]:
    """The Markdown files under `paths` that hold a table marker."""
    for path in paths:
        files = sorted(path.rglob("*.md")) if path.is_dir() else [path]
        for file in files:
            if "<!-- table:" in file.read_text():
                yield file


# --- figure --------------------------------------------------------------------------------


def curves_figure(runs: Sequence[Run], path: Path, colour: str = "dm") -> Path:
    """Target score (mean over the evaluation episodes) against the preference pairs so far,
    one line per run, one panel per target, coloured by the `colour` column; the success
    threshold dashed. Needs Matplotlib (the `study` extra) and groupwise, imported here."""
    from groupwise.study.case_studies.table import Curve, target_curves_figure

    curves = [
        Curve(
            run.get("target"),
            _number(run.get("summary.target.threshold")),
            run.get(colour),
            [_number(r["pairs_total"]) for r in run.rows],
            [_number(r["target_score_mean"]) for r in run.rows],
        )
        for run in runs
    ]
    return target_curves_figure(curves, path, "preference pairs")


# --- command line --------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    verbs = parser.add_subparsers(dest="verb", required=True)
    collect_verb = verbs.add_parser("collect", help="run folders into FOLDER/runs.csv")
    collect_verb.add_argument("folders", nargs="+", type=Path)
    for name, text in (("render", "rewrite the marked tables"), ("check", "fail on a stale table")):
        verb = verbs.add_parser(name, help=text)
        verb.add_argument("paths", nargs="+", type=Path, help="Markdown files or folders")
    figure_verb = verbs.add_parser("figure", help="target score against pairs, per run")
    figure_verb.add_argument("csv", type=Path)
    figure_verb.add_argument("png", type=Path)
    figure_verb.add_argument("--colour", default="dm", help="the column that colours the lines")
    figure_verb.add_argument("--where", nargs="*", default=[], help="column=value|value filters")
    args = parser.parse_args(argv)
    try:
        if args.verb == "collect":
            for folder in args.folders:
                rows, shared = collect(folder)
                write_csv(rows, folder / "runs.csv")
                (folder / SHARED_CONFIG).write_text(json.dumps(shared, indent=1) + "\n")
                runs = len({(row["setup"], row["run"]) for row in rows})
                print(f"{folder / 'runs.csv'}: {runs} runs, {len(rows)} rows")
            return 0
        if args.verb == "figure":
            filters = {k: v.split("|") for k, _, v in (w.partition("=") for w in args.where)}
            curves_figure(select(read_runs(args.csv), filters), args.png, args.colour)
            return 0
        stale = 0
        for file in marked_files(args.paths):
            text = file.read_text()
            fresh = rendered(text, file.parent)
            if fresh == text:
                continue
            if args.verb == "render":
                file.write_text(fresh)
                print(f"{file}: tables rewritten")
            else:
                stale += 1
                sys.stdout.writelines(
                    difflib.unified_diff(
                        text.splitlines(keepends=True),
                        fresh.splitlines(keepends=True),
                        f"{file} (as written)",
                        f"{file} (from its table)",
                    )
                )
        if stale:
            print(f"{stale} file(s) differ from their tables (`render` rewrites them)")
        return 1 if stale else 0
    except (TableError, OSError, KeyError, ValueError) as error:
        print(f"results_table: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
