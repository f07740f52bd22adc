"""The kept policy's decisions (`run.kept_policy`) of the headless cells, from their logs.

Usage: python docs/results/continuous/headless/decisions.py OUT/*.log > decisions.csv
(VARIANT=... names the code the cells ran, as in rounds.csv's `variant` column.)
Each row is one cut that weighed a judged pool's fresh behaviours against its kept share:
how many of each, each ensemble member's mean reward per step on them, the one-sided
Mann-Whitney p that the kept ones are paid more, and what the cut did.
"""

import csv
import os
import re
import sys
from pathlib import Path

LINE = re.compile(
    r"round (?P<round>\d+)'s pool: its (?P<fresh_n>\d+) fresh behaviours paid "
    r"\[(?P<fresh>[^]]*)\] a step, the kept policy's (?P<kept_n>\d+) \[(?P<kept>[^]]*)\] "
    r"\(one-sided Mann-Whitney p = (?P<p>[^ ]+) that the kept ones are paid more\): "
    r"(?P<choice>\w+) \(the kept policy now: (?P<kept_steps>\d+) PPO steps\)"
)
CELL = re.compile(r"(?P<target>.+)-(?P<training>continuous|rounds)-s(?P<seed>\d+)\.log$")
COLUMNS = [
    "target", "training", "variant", "seed", "judged_round", "fresh_n", "kept_n",
    "fresh_paid", "kept_paid", "p_kept_paid_more", "choice", "kept_steps",
]  # fmt: skip


def main(paths: list[str]) -> None:
    writer = csv.DictWriter(sys.stdout, COLUMNS)
    writer.writeheader()
    for path in paths:
        cell = CELL.search(Path(path).name)
        if cell is None:
            continue
        for match in LINE.finditer(Path(path).read_text()):
            writer.writerow({
                **cell.groupdict(),
                "variant": os.environ.get("VARIANT", "default (kept policy)"),
                "judged_round": match["round"],
                "fresh_n": match["fresh_n"],
                "kept_n": match["kept_n"],
                "fresh_paid": " ".join(match["fresh"].split(", ")),
                "kept_paid": " ".join(match["kept"].split(", ")),
                "p_kept_paid_more": match["p"],
                "choice": match["choice"],
                "kept_steps": match["kept_steps"],
            })  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1:])
