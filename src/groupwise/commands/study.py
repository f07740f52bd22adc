"""`groupwise study`: run the simulated study's (env, DM, seed) cells, resumably."""

import argparse
import os
from pathlib import Path

from groupwise.commands.arguments import UsageError, positive_int, writable_dir


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    from groupwise.study.simulation.ablations import ABLATIONS
    from groupwise.study.simulation.profiles import PROFILES

    visible = [name for name, p in PROFILES.items() if not p.hidden]
    profiles = "; ".join(f"{name}: {PROFILES[name].summary}" for name in visible)
    study = subparsers.add_parser(
        "study",
        help="run the simulated study (env × DM × seed cells); rerun to resume",
        description=(
            "Run every (env, DM, seed) cell as its own process into OUT/cells/ENV/DM/seed-K. "
            "Finished cells are skipped and unfinished ones resume from their last round, so "
            f"rerunning the same command continues a stopped study. Profiles: {profiles}."
        ),
    )
    study.add_argument("--envs", nargs="+", help="envs (default: the profile's)")
    study.add_argument("--dms", nargs="+", help="decision-makers (default: the paper's three)")
    study.add_argument("--seeds", type=positive_int, help="seeds 0 … N−1 (default: the profile's)")
    study.add_argument(
        "--profile",
        default="quick",
        choices=list(PROFILES),
        metavar="|".join(visible),
        help="cell size (default: quick)",
    )
    study.add_argument("--out", type=Path, required=True, help="study directory")
    study.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="run on Ray: the cluster at ADDRESS, or a local Ray without one "
        "(OUT must be on a filesystem every node sees)",
    )
    study.add_argument(
        "--workers",
        type=positive_int,
        default=os.cpu_count() or 1,
        help="cells at a time on this machine (default: one per core)",
    )
    study.add_argument(
        "--ablation",
        dest="ablations",
        nargs="+",
        default=[],
        choices=list(ABLATIONS),
        metavar="NAME",
        help="also run every cell under these ablations, each into OUT/NAME/ENV/DM/seed-K: "
        + "; ".join(f"{name}: {a.summary}" for name, a in ABLATIONS.items()),
    )
    study.add_argument(
        "--cap-pairs",
        action="store_true",
        help="the same as --ablation capped (SPEC §8's capped preference pairs)",
    )
    study.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    study.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from groupwise.envs import make_env
    from groupwise.study.simulation.cells import CONDITIONS
    from groupwise.study.simulation.profiles import PROFILES
    from groupwise.study.simulation.runner import (
        RayUnavailableError,
        StudyMismatchError,
        StudySpec,
        plan_jobs,
        run_study,
    )
    from groupwise.teachers import DECISION_MAKERS

    profile = PROFILES[args.profile]
    envs = tuple(args.envs or profile.envs)
    dms = tuple(args.dms or (dm for dm in profile.dms if dm in DECISION_MAKERS))
    for env in envs:
        try:  # made once here: an unknown id or an observation it cannot teach (issue 42)
            make_env(env).close()
        except ValueError as error:
            raise UsageError(str(error)) from None
    if not dms:
        raise UsageError(f"no decision-maker given; choose from {', '.join(DECISION_MAKERS)}")
    unknown = [dm for dm in dms if dm not in DECISION_MAKERS]
    if unknown:
        raise UsageError(f"unknown DM {unknown[0]!r}; choose from {', '.join(DECISION_MAKERS)}")
    if any(name in CONDITIONS for name in (*envs, *dms)):
        raise UsageError(f"env and DM names cannot be {', '.join(CONDITIONS)}")
    ablations = tuple(dict.fromkeys([*args.ablations, *(["capped"] if args.cap_pairs else [])]))
    spec = StudySpec(profile, envs, dms, args.seeds or profile.seeds, ablations)
    out = writable_dir(args.out)
    try:
        plan_jobs(spec, out)  # reject bad values before anything starts
        summary = run_study(
            spec,
            out,
            workers=args.workers,
            backend="local" if args.ray is None else "ray",
            ray_address=args.ray or None,
            show_progress=not args.quiet,
        )
    except (StudyMismatchError, RayUnavailableError, ValueError) as error:
        raise UsageError(str(error)) from None
    print(
        f"{len(summary.outcomes)} cells: {summary.count('done')} run now, "
        f"{summary.count('skipped')} finished before, {summary.count('failed')} failed\n"
        f"study: {out}\nreport: groupwise report {out}"
    )
    for outcome in summary.failed:
        print(f"failed: {outcome.cell.label}: {outcome.error}")
    return 1 if summary.failed else 0
