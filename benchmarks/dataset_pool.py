"""Benchmark: a recorded dataset's pool on screen (issue 42, deliverable 2).

A Minari dataset of `--steps` random-action Hopper-v5 steps (episodes of 1,000 steps: the
env made with ``terminate_when_unhealthy=False``) is recorded with Minari's DataCollector
into a temporary Minari store; then, as the app does it, in this process: the server's
`POST /api/sessions` with ``settings.dataset`` (it reads the dataset to check it), and the
worker's prepare job of round 0 (`Worker.run_next`: the run, `RecordedEpisodes` drawing
2 N windows, the fresh ensemble's most uncertain N, DTW, tree, suggestions, posters and clip
recipes drawn from rebuilt physics states, the round's rows), then the page's first request
(the round's tree). "on screen" is the prepare job plus that request. A warm-up session of
16 behaviours first compiles the DTW kernels and starts the render workers, as in the
long-lived worker; the dataset's in-process cache is cleared before the measured job, so the
job reads the dataset as a fresh worker process would.

    python -m benchmarks.dataset_pool [--n 200] [--steps 100000] [--clip-seconds S]
"""

import argparse
import os
import tempfile
import time
import warnings
from pathlib import Path


def record(root: Path, steps: int, seed: int = 0) -> str:
    """A Minari dataset of `steps` random Hopper-v5 steps (episodes of 1,000 steps) in the
    store `root`, recorded as the tests record theirs (`tests.datasets`); its id."""
    from tests.datasets import build_hopper_dataset

    dataset_id = "bench/hopper-random-v0"
    build_hopper_dataset(root, dataset_id, steps, seed, terminate_when_unhealthy=False)
    return dataset_id


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200, help="behaviours in the pool")
    parser.add_argument("--steps", type=int, default=100_000, help="steps in the dataset")
    parser.add_argument("--clip-seconds", type=float, default=None, help="default: the env's")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")  # Minari's advice on dataset metadata

    from fastapi.testclient import TestClient

    from groupwise.envs import datasets
    from groupwise.server import AppConfig, create_app
    from groupwise.worker.process import Worker

    with tempfile.TemporaryDirectory(prefix="groupwise-dataset-bench-") as tmp:
        root = Path(tmp)
        os.environ["MINARI_DATASETS_PATH"] = str(root / "minari")
        tick = time.perf_counter()
        dataset_id = record(root / "minari", args.steps)
        recorded_s = time.perf_counter() - tick
        config = AppConfig(
            data_dir=root / "data", start_worker=False, allowed_hosts=None,
            static_dir=root / "no-web",
        )  # fmt: skip
        with TestClient(create_app(config)) as client:
            context = client.app.state.context  # type: ignore[attr-defined]  # untyped state
            worker = Worker(context.db, context.data_dir, poll_s=0.1)

            def session(n: int) -> tuple[str, float]:
                settings = {"dataset": f"minari:{dataset_id}", "pool_size": n}
                if args.clip_seconds is not None:
                    settings["clip_seconds"] = args.clip_seconds
                tick = time.perf_counter()
                response = client.post("/api/sessions", json={"settings": settings})
                assert response.status_code == 201, response.text
                return response.json()["id"], time.perf_counter() - tick

            warm, _ = session(16)
            assert worker.run_next()
            datasets._open.cache_clear()
            tick = time.perf_counter()
            loaded = datasets.open_dataset(f"minari:{dataset_id}")
            load_s = time.perf_counter() - tick
            datasets._open.cache_clear()
            sid, create_s = session(args.n)  # the server reads the dataset (cold)
            datasets._open.cache_clear()
            tick = time.perf_counter()
            assert worker.run_next()
            prepare_s = time.perf_counter() - tick
            tree = client.get(f"/api/sessions/{sid}/rounds/0/tree")
            shown_s = time.perf_counter() - tick
            assert tree.status_code == 200, tree.text
            state = client.get(f"/api/sessions/{sid}").json()
            assert state["phase"] == "ready", state["phase"]
            length = state["settings"]["fragment_length"]
            for pool in worker._render.values():
                pool.close()
    print(
        f"dataset: {loaded.steps:,} Hopper-v5 steps in {len(loaded.episodes)} episodes "
        f"(recorded in {recorded_s:.1f} s; read by Minari in {load_s:.2f} s); L = {length}"
    )
    print(f"{'pool':>6} {'create s':>9} {'prepare s':>10} {'on screen s':>12}")
    print(f"{args.n:>6} {create_s:>9.2f} {prepare_s:>10.2f} {shown_s:>12.2f}")
    del warm


if __name__ == "__main__":
    main()
