"""`groupwise report`: tables, statistics and figures of a study directory."""

import argparse
from pathlib import Path

from groupwise.commands.arguments import UsageError, non_negative_int


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    report = subparsers.add_parser(
        "report",
        help="write DIR/report.md and its figures from a study directory",
        description=(
            "Reads every cell under DIR (finished or not) and writes DIR/report.md with the "
            "final-return table beside the paper's, preference pairs and error rates, "
            "training curves and normalised-return statistics, plus PNG figures."
        ),
    )
    report.add_argument("dir", type=Path, help="study directory (as given to `groupwise study`)")
    report.add_argument(
        "--from",
        dest="sources",
        nargs="+",
        type=Path,
        default=[],
        metavar="STUDY_DIR",
        help="read these study directories as one study (e.g. the session and mujoco "
        "profiles, for the paper's table on all six envs) and write the report into DIR",
    )
    report.add_argument(
        "--seed", type=non_negative_int, default=0, help="seed of the bootstrap intervals"
    )
    report.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from groupwise.study.simulation.report import write_report

    for directory in args.sources or [args.dir]:
        if not directory.is_dir():
            raise UsageError(f"no study directory {directory}")
    try:
        path = write_report(args.dir, seed=args.seed, sources=args.sources)
    except (ValueError, OSError) as error:
        raise UsageError(str(error)) from None
    print(f"report: {path}")
    return 0
