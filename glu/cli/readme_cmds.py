"""``glu readme``: write the README's results section from ``results/summary.json`` (or check it)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``readme``."""
    from glu.run.readme import README, SUMMARY

    p = sub.add_parser(
        "readme",
        help="write the README's results section from results/summary.json (a full run on the real data)",
        description="Render the results section of README.md from the summary of make reproduce DATA=… "
        "(every number in it comes from the summary) and write it between its markers; --check only "
        "says whether the README is up to date (exit status 1 if not).",
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
    p.set_defaults(func=_readme)


def _readme(args: argparse.Namespace) -> int:
    from glu.errors import DataError, OutputError

    if args.summary is None or args.readme is None:
        raise OutputError(
            "glu is installed, not a source checkout: give --readme README.md and --summary FILE"
        )
    from glu.run.readme import load_summary, readme_section, render, update_readme

    try:
        summary = load_summary(args.summary)
    except DataError as e:
        if not args.if_complete:
            raise
        print(f"README results section left as it is: {e}")
        return 0
    if args.check:
        current = readme_section(args.readme.read_text(encoding="utf-8"))
        if current == render(summary):
            print(f"{args.readme}: the results section matches {args.summary}")
            return 0
        print(
            f"{args.readme}: the results section differs from {args.summary}; run `glu readme`",
            file=sys.stderr,
        )
        return 1
    changed = update_readme(summary, args.readme)
    print(
        f"{args.readme}: results section {'updated' if changed else 'already up to date'} from {args.summary}"
    )
    return 0
