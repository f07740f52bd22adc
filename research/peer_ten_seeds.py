"""The ten-seed Pendulum comparison at SPEC §7's noise: a table and the per-round curves.

    python research/peer_ten_seeds.py [DIR]   # reads DIR/*.jsonl, writes DIR/curves.png

DIR (default docs/results/peer/ten-seeds) holds one JSON line per seed and learner
(`python -m benchmarks peer` writes them): its seed, final true return and per-round curve.
Prints the table of docs/results/peer/README.md ("Ten seeds").
"""

import argparse
import json
from pathlib import Path

import numpy as np

SIDES = {
    "groupwise.jsonl": "groupwise (default, `cost`)",
    "imitation.jsonl": "imitation 1.0.1",
    "true-reward.jsonl": "PPO on the true reward (same loop)",
}
DEFAULT = Path("docs/results/peer/ten-seeds")


def read_side(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A learner's final returns (seeds,) and curves (seeds, rounds), in seed order."""
    cells = sorted(
        (json.loads(line) for line in path.read_text().splitlines() if line.strip()),
        key=lambda cell: cell["seed"],
    )
    return np.array([c["final_return"] for c in cells]), np.array([c["curve"] for c in cells])


def table(folder: Path) -> list[str]:
    """The Markdown table: per learner the final true return of each seed and its spread."""
    lines = [
        "| learner | seeds | final true return per seed | mean ± SD | median | seeds below −200 |",
        "|---|---:|---|---:|---:|---:|",
    ]
    for name, label in SIDES.items():
        final, _ = read_side(folder / name)
        per_seed = ", ".join(f"{x:,.0f}" for x in final)
        row = (
            f"| {label} | {len(final)} | {per_seed} | {final.mean():.0f} ± "
            f"{final.std(ddof=1):.0f} | {np.median(final):.0f} | {(final < -200).sum()} |"
        )
        lines.append(row.replace("-", "−"))
    return lines


def figure(folder: Path, path: Path) -> Path:
    """Each learner's median true return after each round, quartiles shaded."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 3.6))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    rounds = np.arange(0)
    for name, label in SIDES.items():
        _, curves = read_side(folder / name)
        rounds = np.arange(curves.shape[1])
        line = ax.plot(rounds, np.median(curves, axis=0), marker="o", label=label)[0]
        low, high = np.percentile(curves, 25, axis=0), np.percentile(curves, 75, axis=0)
        ax.fill_between(rounds, low, high, color=line.get_color(), alpha=0.2)
    ax.set_xticks(rounds)
    ax.set_xlabel("round (after its PPO steps)")
    ax.set_ylabel("true return (median, quartiles)")
    ax.set_title("Pendulum-v1, SPEC §7 noise, 10 seeds")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT)
    args = parser.parse_args(argv)
    missing = [name for name in SIDES if not (args.folder / name).is_file()]
    if missing:
        parser.error(f"{args.folder}: no {missing[0]}")
    print("\n".join(table(args.folder)))
    figure(args.folder, args.folder / "curves.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
