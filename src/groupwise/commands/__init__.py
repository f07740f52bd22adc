"""The subcommands of the `groupwise` CLI, one module each with a `register(subparsers)`."""

from collections.abc import Callable

from groupwise.commands import (
    case_study,
    clustering_study,
    export,
    pool,
    report,
    serve,
    study,
    train,
)

COMMANDS: list[Callable] = [
    train.register,
    pool.register,
    clustering_study.register,
    study.register,
    report.register,
    serve.register,
    case_study.register,
    export.register,
]
"""Each adds its subparser and sets `handler` to a function (args) -> exit code."""
