"""Hopper and Walker2d at SPEC §7's noise (issue 41): every learner's final returns and curves.

    python research/peer_locomotion.py [DIR]   # reads DIR/*.jsonl, writes DIR/curves.png

DIR (default docs/results/peer/locomotion) holds the cells `benchmarks/peer.py` wrote, one
JSON line each (env, side, variant, seed, final true return, per-round curve), of any
learners: groupwise's default and its ablations (`peer_groupwise.VARIANTS`), imitation and
PPO on the true reward. Prints the table of docs/results/peer/README.md: per env and
learner the seeds, mean ± SD, median, the seeds that took off (`TOOK_OFF`) and a two-sided
Mann–Whitney test of each groupwise learner's final returns against imitation's.
"""

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy.stats import mannwhitneyu

DEFAULT = Path("docs/results/peer/locomotion")
TOOK_OFF = {"Hopper-v4": 600.0, "Walker2d-v4": 600.0}
"""A final return above which a seed hops or walks on past its first stumble: the runs that
stay down level off at 200–300 (Hopper) and below 450 (Walker2d)."""
IMITATION = "imitation"
MAIN = ("std-step", "return-scale", IMITATION, "true-reward")
"""The learners drawn thick: groupwise now and before, imitation, the ceiling."""


def read_cells(folder: Path) -> dict[tuple[str, str], list[dict]]:
    """(env, learner) → its cells in seed order; a learner is groupwise's variant name or
    "imitation"."""
    cells: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for path in sorted(folder.glob("*.jsonl")):
        for line in path.read_text().splitlines():
            if line.strip():
                cell = json.loads(line)
                cells[cell["env"], cell["variant"]].append(cell)
    return {key: sorted(found, key=lambda c: c["seed"]) for key, found in cells.items()}


def took_off(env: str, final: np.ndarray) -> str:
    """How many seeds ended above `TOOK_OFF` of the env ("–" for other envs)."""
    if env not in TOOK_OFF:
        return "–"
    return f"{int((final > TOOK_OFF[env]).sum())}/{len(final)}"


def table(cells: dict[tuple[str, str], list[dict]]) -> list[str]:
    lines = [
        "| env | learner | seeds | mean ± SD | median | took off | vs imitation (p) |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for env, learner in sorted(cells, key=lambda k: (k[0], k[1] != "default", k[1])):
        final = np.array([c["final_return"] for c in cells[env, learner]])
        theirs = cells.get((env, IMITATION))
        if learner == IMITATION or theirs is None:
            test = "–"
        else:
            other = [c["final_return"] for c in theirs]
            test = f"{mannwhitneyu(final, other).pvalue:.2f}"
        spread = f"{final.std(ddof=1):.0f}" if len(final) > 1 else "–"
        lines.append(
            f"| {env} | {learner} | {len(final)} | {final.mean():.0f} ± {spread} | "
            f"{np.median(final):.0f} | {took_off(env, final)} | {test} |"
        )
    return lines


def plot(cells: dict[tuple[str, str], list[dict]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    envs = sorted({env for env, _ in cells})
    fig, axes = plt.subplots(1, len(envs), figsize=(5.0 * len(envs), 3.6), squeeze=False)
    learners = sorted({learner for _, learner in cells})
    colours = {learner: f"C{i % 10}" for i, learner in enumerate(learners)}  # one per learner
    for ax, env in zip(axes[0], envs, strict=True):
        for (of, learner), found in sorted(cells.items()):
            if of != env:
                continue
            curves = np.array([c["curve"] for c in found])
            rounds = np.arange(1, curves.shape[1] + 1)
            thick = learner in MAIN
            ax.plot(
                rounds,
                curves.mean(axis=0),
                marker="o" if thick else None,
                lw=2.2 if thick else 1.0,
                alpha=1.0 if thick else 0.6,
                color=colours[learner],
                label=f"{learner} ({len(found)})",
            )
        ax.set_title(env)
        ax.set_xticks(rounds)
        ax.set_xlabel("round")
        ax.set_ylabel("mean true return (10 episodes a seed)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT)
    args = parser.parse_args()
    cells = read_cells(args.folder)
    print("\n".join(table(cells)))
    plot(cells, args.folder / "curves.png")


if __name__ == "__main__":
    main()
