"""The commands of ``glu``, where each is defined, and the line ``glu --help`` gives it.

:func:`glu.cli.build_parser` imports only the module of the command being run (a module's imports — pandas,
SciPy, the models — cost seconds on a busy machine); ``glu --help`` and an unknown command import none. This
table, which imports nothing, is the one place a command's one-line help is written: each module's
``register`` reads it from here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    import argparse
    from collections.abc import Callable


class Command(NamedTuple):
    """Where a top-level command is defined, and its one line in ``glu --help``."""

    module: str
    help: str


COMMANDS: dict[str, Command] = {
    "data": Command("glu.cli.data_cmds", "fetch, synthesise or inspect data"),
    "bn": Command("glu.cli.bn_cmds", "learn, import or inspect the Affordance–Words network"),
    "query": Command("glu.cli.bn_cmds", "posterior marginals given hard and soft evidence"),
    "gestures": Command("glu.cli.gesture_cmds", "inspect and segment hand-trajectory logs"),
    "hmm": Command("glu.cli.gesture_cmds", "train gesture HMMs"),
    "recognize": Command("glu.cli.gesture_cmds", "posterior p_HMM(A | G) of a gesture in a hand log"),
    "reproduce": Command(
        "glu.cli.reproduce_cmds",
        "run every notebook: figures, recordings, results summary, documentation site",
    ),
    "run": Command(
        "glu.cli.reproduce_cmds", "run one notebook headless with other parameters (into its scratch folder)"
    ),
    "describe": Command(
        "glu.cli.language_cmds", "the N best sentences describing a situation (grammar + word probabilities)"
    ),
    "anticipate": Command(
        "glu.cli.anticipate_cmds",
        "effect anticipation: HMM scores per frame, p_comb(ObjVel) every 5 frames, a description",
    ),
    "readme": Command(
        "glu.cli.readme_cmds",
        "write the generated sections of the README and docs/ (story table, results, commands, speed)",
    ),
    "evaluate": Command(
        "glu.cli.eval_cmds", "measure every fusion strategy on a simulated corpus (Dask sweep)"
    ),
    "corpus": Command("glu.cli.eval_cmds", "write a simulated corpus of episodes to Parquet"),
    "correspondence": Command(
        "glu.cli.correspondence_cmds",
        "run notebook 10's synthetic correspondence study (Dask) and save its tables",
    ),
    "learn-gestures": Command(
        "glu.cli.learn_cmds",
        "learn gesture HMMs from unlabelled episodes, labelled by the affordance network",
    ),
    "learning-curves": Command(
        "glu.cli.learn_cmds",
        "the long runs of learning from effects (Dask, one task per seed): what notebook 12 reads",
    ),
}
"""Every top-level command, in the order ``glu --help`` lists them."""


def add_command(
    sub: argparse._SubParsersAction,
    name: str,
    description: str,
    func: Callable[[argparse.Namespace], int] | None = None,
    help: str | None = None,
    epilog: str | None = None,
) -> argparse.ArgumentParser:
    """The parser of the command ``name``, which runs ``func``: ``description`` (and ``epilog``) for its
    ``--help``, ``help`` for its one line (default: the top-level command's, from :data:`COMMANDS`)."""
    parser = sub.add_parser(name, help=help or COMMANDS[name].help, description=description, epilog=epilog)
    if func is not None:
        parser.set_defaults(func=func)
    return parser


def add_group(sub: argparse._SubParsersAction, name: str, description: str) -> argparse._SubParsersAction:
    """The top-level command group ``name`` (``glu NAME SUBCOMMAND``, a subcommand required), as
    :func:`add_command`: returns what its subcommands are added to. The subcommand given is
    ``args.NAME_command``."""
    group = add_command(sub, name, description).add_subparsers(dest=f"{name}_command", metavar="SUBCOMMAND")
    group.required = True
    return group
