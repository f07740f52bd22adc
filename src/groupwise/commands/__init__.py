"""The subcommands of the `groupwise` CLI, one module each with a `register(subparsers)`."""

from collections.abc import Callable

from groupwise.commands import train

COMMANDS: list[Callable] = [train.register]
"""Each adds its subparser and sets `handler` to a function (args) -> exit code."""
