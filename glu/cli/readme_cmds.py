"""``glu readme``: write the README's generated sections (or check them).

The story table comes from the notebooks' manifests (:mod:`glu.run.generated`), the results section from
``results/summary.json`` (:mod:`glu.run.readme`), the speed page's tables from the benchmarks' JSON
(:mod:`glu.run.speed`).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from glu.cli.commands import add_command


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``readme``."""
    from glu.run.readme import README, SUMMARY

    p = add_command(
        sub,
        "readme",
        "Write the README's story table (from the notebooks' manifests), its results section "
        "(from the summary of a full make reproduce on the real data: every number in it comes from the "
        "summary), and the command table of docs/cli.md and the tables of docs/speed.md (from the "
        "benchmarks' results), each between its markers; --check only says whether they are up to date "
        "(exit status 1 if not).",
        _readme,
    )
    p.add_argument(
        "--summary", type=Path, default=SUMMARY, help="summary.json (default: results/summary.json)"
    )
    p.add_argument("--readme", type=Path, default=README, help="the README to update (default: README.md)")
    p.add_argument("--check", action="store_true", help="do not write; exit 1 if the README differs")
    p.add_argument(
        "--if-complete",
        action="store_true",
        help="do nothing (exit 0) unless the summary is a full run on the real data (for make reproduce)",
    )


def _readme(args: argparse.Namespace) -> int:
    from glu.errors import DataError, OutputError

    if args.summary is None or args.readme is None:
        raise OutputError(
            "glu is installed, not a source checkout: give --readme README.md and --summary FILE"
        )
    stale = _other_pages(args)
    from glu.run.readme import load_summary, readme_section, render, update_readme

    try:
        summary = load_summary(args.summary)
    except DataError as e:
        if not args.if_complete:
            raise
        print(f"README results section left as it is: {e}")
        return 1 if stale else 0
    if args.check:
        if readme_section(args.readme.read_text(encoding="utf-8")) != render(summary):
            print(
                f"{args.readme}: the results section differs from {args.summary}; run `glu readme`",
                file=sys.stderr,
            )
        elif not stale:
            print(f"{args.readme}: the results section matches {args.summary}")
            return 0
        return 1
    changed = update_readme(summary, args.readme)
    print(
        f"{args.readme}: results section {'updated' if changed else 'already up to date'} from {args.summary}"
    )
    if (summary.get("provenance") or {}).get("modified"):  # figures no commit can make again
        print(
            f"note: this run was made by {summary['made_by']}: its figures name no commit that reproduces "
            "them; commit the code, then run `make reproduce` again before committing figures/",
            file=sys.stderr,
        )
    return 0


COMMANDS_BEGIN = "<!-- BEGIN commands: written by `glu readme` from the parser of glu.cli; edit its help -->"
COMMANDS_END = "<!-- END commands -->"


def command_table() -> str:
    """Every command and subcommand of ``glu`` with its one-line help, as a Markdown table
    (``docs/cli.md``)."""
    from glu.cli import build_parser

    def walk(parser: argparse.ArgumentParser, path: list[str]):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                helps = {a.dest: a.help for a in action._choices_actions}
                for name, sub in action.choices.items():
                    yield " ".join([*path, name]), helps.get(name) or ""
                    yield from walk(sub, [*path, name])

    rows = ["| command | what it does |", "|---|---|"]
    rows += [f"| `glu {c}` | {h.replace('|', chr(92) + '|')} |" for c, h in walk(build_parser(), [])]
    return "\n".join(rows)


def _pages() -> list[tuple[Path, str, str, Any]]:
    """The checkout's generated sections that need no summary: (page, begin, end, what writes it)."""
    from glu.run import generated, speed
    from glu.run.readme import README

    docs = README.parent / "docs"
    return [
        (
            README,
            generated.STORY_BEGIN,
            generated.STORY_END,
            lambda: generated.story_table(generated.manifests()),
        ),
        (docs / "cli.md", COMMANDS_BEGIN, COMMANDS_END, command_table),
        (docs / "speed.md", speed.BEGIN, speed.END, lambda: speed.render(speed.load_results())),
    ]


def _other_pages(args: argparse.Namespace) -> bool:
    """Write (or, with --check, compare) the sections that need no summary; True if one is stale.

    Only for the checkout's own README: a README given elsewhere (a test's) gets its results section only.
    """
    from glu.run import generated
    from glu.run.readme import README

    # os.path.realpath, not Path.resolve: a symlink loop given as --readme is then read, and refused as such
    if README is None or os.path.realpath(args.readme) != os.path.realpath(README):
        return False
    stale = False
    for page, begin, end, write in _pages():
        new, name = write(), page.relative_to(README.parent)
        if args.check:
            if generated.section(page.read_text(encoding="utf-8"), begin, end, str(name)) != new.strip():
                print(f"{name}: a generated section is out of date; run `glu readme`", file=sys.stderr)
                stale = True
        elif generated.replace_section(page, begin, end, new):
            print(f"{name}: generated section updated")
    return stale
