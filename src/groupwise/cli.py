"""The `groupwise` command line: a thin shell that parses, validates and calls the core."""

import argparse
import logging
import sys
from collections.abc import Callable, Sequence

import torch

from groupwise.commands import COMMANDS
from groupwise.commands.arguments import UsageError

EXTRAS = {
    "fastapi": "app",
    "uvicorn": "app",
    "sqlalchemy": "app",
    "pyarrow": "app",
    "psycopg": "postgres",
    "matplotlib": "study",
    "sklearn": "study",
    "ray": "study",
}
"""A package of an optional extra (pyproject.toml) → the extra that installs it."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="groupwise",
        description="RLHF with interactive groupwise comparison of agent behaviours.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug detail")
    subparsers = parser.add_subparsers(dest="command", required=True)
    for register in COMMANDS:
        register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    # Our own log lines at INFO; other libraries' only when they warn.
    logging.basicConfig(
        level=logging.WARNING, format="%(asctime)s %(levelname)s %(name)s: %(message)s"
    )
    logging.getLogger("groupwise").setLevel(logging.DEBUG if args.verbose else logging.INFO)
    # Our nets are tiny: torch's intra-op threads only contend (a (2, 5) softmax took 7.8 ms
    # with 2 threads on a busy 2-core machine, 2 µs with one).
    torch.set_num_threads(1)
    handler: Callable[[argparse.Namespace], int] = args.handler
    try:
        return handler(args)
    except UsageError as error:
        print(f"groupwise: error: {error}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as error:
        extra = EXTRAS.get((error.name or "").split(".")[0])
        if extra is None:
            raise
        hint = f"pip install 'groupwise[{extra}]'"
        print(f"groupwise: error: {args.command} needs {error.name}: {hint}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("groupwise: interrupted; continue with --resume", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
