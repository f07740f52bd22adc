"""groupwise against HumanCompatibleAI `imitation` 1.0.1, side by side, from the same labels.

    python -m benchmarks peer                          # every env, 5 seeds, both sides
    python benchmarks/peer.py --envs Pendulum-v1 --seeds 3 --variants default,epochs10
    python benchmarks/peer.py --no-imitation --variants ...   # ablations of groupwise only
    python benchmarks/peer.py --no-imitation --variants true-reward  # PPO on the true reward
    python benchmarks/peer.py --envs Pendulum-v1 --noise spec  # SPEC §7's noise on both sides

Same budget on both sides: 200 pairwise comparisons in 5 rounds (20 in round 0, then 45 a
round), 20,480 PPO steps after each round (102,400 in all), identical PPO settings, a
3-member bagged 64-64 reward ensemble, active selection of the most disputed of 10 candidate
pairs, and one teacher's noise on both sides (`--noise`):

- `boltzmann` (the default): Boltzmann-rational labels, β = 1 on the fragments' true returns
  (imitation's `SyntheticGatherer(temperature=1)`, our `PairwiseTeacher(sigma=0, beta=1)`),
  nearly noise-free on Pendulum's return scale;
- `spec`: SPEC §7's teacher on ours (`PairwiseTeacher(sigma=σ)`: each fragment's return
  perceived with Normal(0, (L·σ)²) noise, the higher wins; σ = `--sigma`, 0.25 by default)
  and on imitation's the logistic temperature that matches it, √2·L·σ / 1.702 (the
  difference of two perceived returns has sd √2·L·σ, and Φ(x) ≈ σ(1.702 x)); fragments of
  SPEC's L = 30 steps (`--fragment-length`) and imitation's round 0 trained 10× the epochs,
  as ours is (its own default is 200×).

The final return is the mean
over 10 deterministic episodes with reset seeds 10,000 … 10,009, the same on both sides; the
per-round curve uses the same episodes after each round.

imitation runs in its own venv (`.peer-venv/`, created on first use from the package
registry with `scripts/install-torch.sh`: it pins gymnasium 0.29 and Stable-Baselines3 2.2,
which groupwise's venv cannot hold); groupwise's envs are imported there from `src/`. Each
cell is a subprocess; two run at a time (one per core). Prints a table per env (wall, PPO
and non-PPO seconds, final true return ± SD over seeds, rounds after the peak where the
return fell) and writes the per-round curves to `peer.png` and every cell to `peer.jsonl`
in `--out`. About 45 min for the four envs without MuJoCo locomotion (Pendulum, Reacher,
MountainCarContinuous, GridWorld; 5 seeds × 2 sides) on two cores; Hopper-v4 and Walker2d-v4
(`env_kwargs` in `ENVS`: a fall ends no episode, as imitation's fixed horizons need) take
longer.
"""

import argparse
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
VENV = REPO / ".peer-venv"
PINS = ["imitation==1.0.1", "gymnasium[mujoco]==0.29.1", "stable-baselines3==2.2.1"]

ENVS = {
    # standard Gymnasium envs with fixed horizons and dense rewards
    "Pendulum-v1": {"fragment_length": 25},
    "Reacher-v4": {"fragment_length": 10},
    # MuJoCo locomotion (v4: in gymnasium 0.29 and 1.x alike); a fall does not end the episode
    # (imitation needs fixed horizons), it only stops the healthy reward: 1,000 steps each.
    # Fragments of 50 steps (0.4 s, about a stride: a guess, not measured) unless --noise spec
    # sets SPEC's 30
    "Hopper-v4": {"fragment_length": 50, "env_kwargs": {"terminate_when_unhealthy": False}},
    "Walker2d-v4": {"fragment_length": 50, "env_kwargs": {"terminate_when_unhealthy": False}},
    # two of ours
    "MountainCarContinuous": {
        "fragment_length": 25,
        "groupwise_env": "groupwise.envs.mountain_car:DenseMountainCarEnv",
        "imitation_id": "groupwise/MountainCarContinuous-v0",
        "horizon": 250,
    },
    "GridWorld": {
        "fragment_length": 30,
        "groupwise_env": "groupwise.envs.gridworld:GridWorldEnv",
        "imitation_id": "groupwise/GridWorld-v0",
        "horizon": 1000,
    },
}

NOISES = ("boltzmann", "spec")
"""The teachers `--noise` chooses between (module docstring)."""
LOGISTIC_PROBIT = 1.702
"""Φ(x) ≈ σ(1.702 x): the logistic scale that matches a normal CDF."""

BASE = {
    "comparisons": 200,
    "rounds": 5,
    "initial_fraction": 0.1,
    "steps_per_round": 20_480,
    "exploration_fraction": 0.05,
    "candidate_pairs": 10,
    "ensemble_size": 3,
    "reward_hidden": [64, 64],
    "noise": "boltzmann",
    "boltzmann_beta": 1.0,
    "sigma": 0.0,
    "imitation_initial_epoch_multiplier": 200.0,
    "eval_seeds": list(range(10_000, 10_010)),
    "ppo": {
        "n_envs": 8,
        "n_steps": 256,
        "batch_size": 64,
        "n_epochs": 10,
        "learning_rate": 2e-3,
        "clip_range": 0.1,
        "gamma": 0.97,
        "gae_lambda": 0.95,
        "ent_coef": 0.01,
        "net_arch": [32, 32],
    },
}


def imitation_python() -> Path:
    """imitation's venv, created (pinned, CPU torch) when missing."""
    python = VENV / "bin" / "python"
    if python.exists():
        return python
    subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
    subprocess.run(["bash", str(REPO / "scripts" / "install-torch.sh"), str(python)], check=True)
    subprocess.run([str(python), "-m", "pip", "install", "-q", *PINS], check=True)
    return python


def noise_spec(noise: str, sigma: float, fragment_length: int | None) -> dict:
    """The spec fields of a teacher (`NOISES`): the same noise on both sides."""
    if noise == "boltzmann":
        return {} if fragment_length is None else {"fragment_length": fragment_length}
    length = 30 if fragment_length is None else fragment_length
    return {
        "noise": "spec",
        "sigma": sigma,
        "fragment_length": length,
        # imitation's temperature: the logistic match of the perceived returns' difference
        "boltzmann_beta": float(np.sqrt(2.0) * length * sigma / LOGISTIC_PROBIT),
        "imitation_initial_epoch_multiplier": 10.0,
    }


def cell_spec(env: str, seed: int, variant: str, teacher: dict | None = None) -> dict:
    extra = ENVS[env]
    spec = {**BASE, **extra, "env": env, "seed": seed, "variant": variant, "src": str(REPO / "src")}
    return {**spec, **(teacher or {})}


def run_cell(side: str, spec: dict, python: Path) -> dict:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MUJOCO_GL": "disable", "CUDA_VISIBLE_DEVICES": ""}
    if side == "imitation":
        spec = {**spec, "env": spec.get("imitation_id", spec["env"])}
        script = REPO / "benchmarks" / "peer_imitation.py"
    else:
        script = REPO / "benchmarks" / "peer_groupwise.py"
    done = subprocess.run(
        [str(python), str(script), json.dumps(spec)],
        capture_output=True,
        text=True,
        env=env,
        cwd=REPO,
        check=False,
    )
    if done.returncode != 0:
        raise RuntimeError(
            f"{side} {spec['env']} seed {spec['seed']} failed:\n{done.stderr[-3000:]}"
        )
    result = json.loads(done.stdout.strip().splitlines()[-1])
    result["env"] = spec.get("imitation_label", result["env"])
    return result


def fell_after_peak(curve: list[float]) -> float:
    """How far the last round's return is below the best round's."""
    return float(max(curve) - curve[-1]) if curve else float("nan")


def table(results: list[dict]) -> str:
    rows = [
        "| env | side | seeds | wall s | PPO s | non-PPO s | final true return | SD | "
        "last vs best round |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    keys = sorted({(r["env"], r["variant"]) for r in results})
    for env, variant in keys:
        cells = [r for r in results if r["env"] == env and r["variant"] == variant]
        final = np.array([r["final_return"] for r in cells])
        rows.append(
            f"| {env} | {variant} | {len(cells)} | "
            f"{np.mean([r['wall_s'] for r in cells]):.1f} | "
            f"{np.mean([r['ppo_s'] for r in cells]):.1f} | "
            f"{np.mean([r['non_ppo_s'] for r in cells]):.1f} | {final.mean():.1f} | "
            f"{final.std(ddof=1) if len(final) > 1 else float('nan'):.1f} | "
            f"−{np.mean([fell_after_peak(r['curve']) for r in cells]):.1f} |"
        )
    return "\n".join(rows)


def plot(results: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    envs = sorted({r["env"] for r in results})
    fig, axes = plt.subplots(1, len(envs), figsize=(4.2 * len(envs), 3.4), squeeze=False)
    for ax, env in zip(axes[0], envs, strict=True):
        for variant in sorted({r["variant"] for r in results if r["env"] == env}):
            curves = [r["curve"] for r in results if r["env"] == env and r["variant"] == variant]
            length = min(len(c) for c in curves)
            data = np.array([c[:length] for c in curves])
            x = np.arange(1, length + 1)
            ax.plot(x, data.mean(axis=0), marker="o", label=variant)
            ax.fill_between(x, data.min(axis=0), data.max(axis=0), alpha=0.15)
        ax.set_title(env)
        ax.set_xlabel("round")
        ax.set_ylabel("true return (10 episodes)")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", default=",".join(ENVS))
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--first-seed", type=int, default=0, help="seeds first … first+N−1")
    parser.add_argument(
        "--variants", default="default", help="groupwise variants (peer_groupwise.VARIANTS)"
    )
    parser.add_argument("--no-imitation", action="store_true")
    parser.add_argument("--no-groupwise", action="store_true", help="imitation's cells only")
    parser.add_argument("--noise", choices=NOISES, default="boltzmann", help="the teacher")
    parser.add_argument("--sigma", type=float, default=0.25, help="--noise spec: σ per step")
    parser.add_argument(
        "--fragment-length", type=int, default=None, help="L on every env (spec noise: 30)"
    )
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=REPO / "runs" / "peer")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    envs = args.envs.split(",")
    unknown = [e for e in envs if e not in ENVS]
    if unknown:
        raise SystemExit(f"unknown env {unknown[0]!r}; choose from {', '.join(ENVS)}")
    ours = Path(sys.executable)
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    variants = [] if args.no_groupwise else args.variants.split(",")
    teacher = noise_spec(args.noise, args.sigma, args.fragment_length)
    jobs = [
        ("groupwise", cell_spec(env, seed, variant, teacher), ours)
        for env in envs
        for variant in variants
        for seed in seeds
    ]
    if not args.no_imitation:
        theirs = imitation_python()
        jobs += [
            (
                "imitation",
                {**cell_spec(env, seed, "imitation", teacher), "imitation_label": env},
                theirs,
            )
            for env in envs
            for seed in seeds
        ]
    log = args.out / "peer.jsonl"
    results = []
    with ThreadPoolExecutor(args.jobs) as pool, log.open("a") as handle:
        for result in pool.map(lambda job: run_cell(*job), jobs):
            results.append(result)
            handle.write(json.dumps({**result, "noise": args.noise, **teacher}) + "\n")
            handle.flush()
            print(
                f"{result['side']:9} {result['env']:22} {result['variant']:12} seed "
                f"{result['seed']}: {result['final_return']:10.1f} in {result['wall_s']:.0f} s",
                flush=True,
            )
    print()
    print(table(results))
    plot(results, args.out / "peer.png")
    print(f"\nper-round curves: {args.out / 'peer.png'}; cells: {log}")


if __name__ == "__main__":
    main()
