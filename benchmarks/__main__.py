"""Run every benchmark (or those named) and print their tables: `python -m benchmarks [NAME]`."""

import importlib
import sys

BENCHMARKS = [
    "ppo_throughput",
    "render_fps",
    "dtw",
    "pool_prep",
    "submit_latency",
    "web_render",
    "suggestions",
]
ON_DEMAND = [
    "peer",
    "faults",
    "fuzz",
    "continuous",
    "app_teacher",
    "tree_balance",
    "dtw_options",
]
"""Run only when named: `peer` (groupwise against imitation) takes about 45 minutes,
`faults` (100 kills of server or worker under load, then `fuzz`) about 25, `fuzz`
(schemathesis, 10,000 requests to the live API) about 5, `continuous` (a person's pace on a
continuous session, then PPO's one-core throughput) about 5, `tree_balance` (short training
runs of four envs, then their pools' trees) about 30 on 2 cores, `dtw_options` (a band or
a coarser time step against exact DTW on Hopper pools) about 5, `app_teacher` (a simulated
person teaching three targets × three seeds through a live server, 20 minutes each) about 200."""


def main(names: list[str]) -> None:
    for name in names or BENCHMARKS:
        if name not in BENCHMARKS + ON_DEMAND:
            known = ", ".join(BENCHMARKS + ON_DEMAND)
            raise SystemExit(f"unknown benchmark {name!r}; choose from {known}")
        print(f"\n## {name}\n", flush=True)
        module = importlib.import_module(f"benchmarks.{name}")
        if name in ON_DEMAND:
            module.main([])
        else:
            module.main()


if __name__ == "__main__":
    main(sys.argv[1:])
