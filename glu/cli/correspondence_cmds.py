"""``glu correspondence``: the synthetic study of notebook 10 (the correspondence problem), as a grid on Dask
(what it runs and writes: its description below; the tables' key and provenance: :mod:`glu.saved`)."""

from __future__ import annotations

import argparse

from glu.cli.commands import add_command
from glu.cli.common import add_out_option, command_line, positive_int


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``correspondence`` command."""
    p = add_command(
        sub,
        "correspondence",
        "Run the synthetic study of notebook 10 with its default parameters (every seed, "
        "training source, feature set and condition; the ideal and the occluding tracker), one task per "
        "seed on a LocalCluster, and write its tables with their key and provenance to -o DIR, where "
        "the notebook finds them (sweeps/10_correspondence/study: make sweeps).",
        _run,
    )
    add_out_option(p, "DIR", "folder for the tables", folder=True)
    p.add_argument(
        "--workers", type=positive_int, metavar="N", help="LocalCluster workers (default: in this process)"
    )


def notebook_settings():
    """The study's settings from notebook 10's parameters cell (its defaults)."""
    from glu.paths import NOTEBOOKS_DIR
    from glu.run.parameters import read_spec
    from glu.studies.correspondence.grid import settings_from_parameters

    spec = {k: p.default for k, p in read_spec(NOTEBOOKS_DIR / "10_correspondence.py").items()}
    return settings_from_parameters(spec)


def _run(args: argparse.Namespace) -> int:
    from glu.studies.correspondence.grid import run_study, write_tables

    settings = notebook_settings()
    tables = run_study(settings, workers=args.workers or 0)
    folder = write_tables(args.out, tables, settings.key(), command_line())
    print(f"{len(tables[0])} rows over {len(settings.seeds)} seeds → {folder}")
    return 0
