"""The ten-seed Pendulum comparison at SPEC §7's noise: a table and the per-round curves.

    python docs/results/peer/ten-seeds/plot.py   # reads the *.jsonl here, writes curves.png
"""

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

HERE = Path(__file__).parent
SIDES = {
    "groupwise.jsonl": "groupwise (default, `cost`)",
    "imitation.jsonl": "imitation 1.0.1",
    "true-reward.jsonl": "PPO on the true reward (same loop)",
}


def main() -> None:
    print("| learner | seeds | final true return per seed | mean ± SD | median | seeds below −200 |")
    print("|---|---:|---|---:|---:|---:|")
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for name, label in SIDES.items():
        cells = sorted((json.loads(line) for line in open(HERE / name)), key=lambda c: c["seed"])
        final = np.array([c["final_return"] for c in cells])
        curves = np.array([c["curve"] for c in cells])
        per_seed = ", ".join(f"{x:,.0f}".replace("-", "−") for x in final)
        print(f"| {label} | {len(final)} | {per_seed} | {final.mean():.0f} ± {final.std(ddof=1):.0f} "
              f"| {np.median(final):.0f} | {(final < -200).sum()} |".replace("-", "−"))
        rounds = np.arange(curves.shape[1])
        line = ax.plot(rounds, np.median(curves, axis=0), marker="o", label=label)[0]
        ax.fill_between(rounds, np.percentile(curves, 25, axis=0),
                        np.percentile(curves, 75, axis=0), color=line.get_color(), alpha=0.2)
    ax.set_xticks(rounds)
    ax.set_xlabel("round (after its PPO steps)")
    ax.set_ylabel("true return (median, quartiles)")
    ax.set_title("Pendulum-v1, SPEC §7 noise, 10 seeds")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(HERE / "curves.png", dpi=120)


if __name__ == "__main__":
    main()
