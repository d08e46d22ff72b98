"""The ``glu`` command line: thin wrappers over the package, one module per group of commands.

Bad input (a missing file, an unknown node or value, impossible evidence, …) prints one line on stderr —
what was wrong, where, what is allowed — and exits with status 2, never with a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from glu import __version__
from glu.errors import GluError

COMMAND_MODULES: tuple[str, ...] = (
    "glu.cli.data_cmds",
    "glu.cli.bn_cmds",
    "glu.cli.gesture_cmds",
    "glu.cli.reproduce_cmds",
    "glu.cli.language_cmds",
)
"""Each module defines ``register(subparsers)``; handlers import heavy libraries lazily."""

EXIT_BAD_INPUT = 2


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line (plus where to find help), exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser of ``glu``."""
    parser = OneLineParser(
        prog="glu",
        description="Gestures, language and affordances: reproduce Saponaro et al. (GLU 2017, TCDS 2020).",
    )
    parser.add_argument("--version", action="version", version=f"glu {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser)
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``glu`` console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    sub = getattr(args, f"{args.command}_command", None)
    name = f"glu {args.command}" + (f" {sub}" if sub else "")
    try:
        status = args.func(args)
    except GluError as e:
        print(f"{name}: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    return int(status or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
