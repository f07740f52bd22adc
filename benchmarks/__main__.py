"""Run every benchmark (or those named) and print their tables: `python -m benchmarks [NAME]`."""

import importlib
import sys

BENCHMARKS = ["ppo_throughput", "render_fps", "dtw", "pool_prep", "submit_latency", "web_render"]


def main(names: list[str]) -> None:
    for name in names or BENCHMARKS:
        if name not in BENCHMARKS:
            raise SystemExit(f"unknown benchmark {name!r}; choose from {', '.join(BENCHMARKS)}")
        print(f"\n## {name}\n", flush=True)
        importlib.import_module(f"benchmarks.{name}").main()


if __name__ == "__main__":
    main(sys.argv[1:])
