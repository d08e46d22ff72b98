"""``glu reproduce`` runs every notebook headless and publishes all figures, recordings and results;
``glu run`` runs one notebook with other parameters, into its scratch folder."""

from __future__ import annotations

import argparse
from pathlib import Path

from glu.cli.commands import add_command
from glu.cli.common import (
    add_data_option,
    add_json_option,
    chosen,
    json_text,
    positive_int,
    require_extra,
    seed,
)

NOTEBOOK_MODULES = ("papermill", "jupytext", "ipykernel", "nbconvert", "rerun")
"""What running the notebooks needs: the extra ``glu[notebooks]``."""
SITE_MODULES = ("sphinx", "myst_nb", "pydata_sphinx_theme")
"""What building the documentation site needs: the extra ``glu[docs]`` (in ``glu[notebooks]``)."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``reproduce`` and ``run`` commands."""
    p = add_command(
        sub,
        "reproduce",
        "Run every notebook headless, in parallel kernels, then write the results summary and "
        "the documentation site; publish the whole run (figures, recordings, results, models, executed "
        "notebooks, summary, site) at once, only when every notebook succeeded: a failed or interrupted run "
        "leaves the last published run as it was. Nothing glu did not write is replaced.",
        _reproduce,
    )
    add_data_option(p)
    p.add_argument("--quick", action="store_true", help="small, fast runs (as the tests do)")
    p.add_argument(
        "-o",
        "--out",
        type=Path,
        metavar="DIR",
        help="write figures/, recordings/, results/, models/, notebooks/, site/ here "
        "(default: the project's folders in a source checkout; required when glu is installed)",
    )
    p.add_argument("-j", "--jobs", type=positive_int, default=2, help="notebooks run in parallel (default 2)")
    p.add_argument(
        "--only", nargs="+", metavar="NOTEBOOK", help="run only these notebooks (names or numbers)"
    )
    p.add_argument("--seed", type=seed, default=0, help="seed passed to every notebook (default 0)")
    p.add_argument("--no-site", action="store_true", help="skip the documentation site (build/site/)")
    p.add_argument(
        "--force",
        action="store_true",
        help="where -o DIR holds a folder or file glu did not write (figures/, site/, …), leave it untouched "
        "and publish that part in DIR/.glu-runs/current/ only (default: refuse, naming it)",
    )

    r = add_command(
        sub,
        "run",
        (
            "Run one notebook headless, showing each cell as it starts on stderr (--quiet: nothing). "
            "Parameters are checked against the notebook's parameters cell before anything executes. "
            "Outputs go to a new folder build/scratch/NOTEBOOK/DATE-TIME/ unless -o DIR is given (a folder "
            "glu reproduce published into is refused); only glu reproduce publishes into "
            'figures/, results/, recordings/, models/. --json prints {"notebook", "executed", "outputs"} '
            "(with --list: the parameters)."
        ),
        _run,
    )
    r.add_argument("notebook", help="the notebook's name or number (e.g. 08_tcds_figures or 8)")
    r.add_argument(
        "-p",
        "--parameter",
        nargs=2,
        action="append",
        default=[],
        metavar=("NAME", "VALUE"),
        help="set a parameter (repeatable); glu run NOTEBOOK --list shows them",
    )
    add_data_option(r)
    r.add_argument(
        "-o",
        "--out",
        type=Path,
        metavar="DIR",
        help="output folder (default: a new build/scratch/NOTEBOOK/DATE-TIME/)",
    )
    r.add_argument(
        "--quick", action="store_true", help="the quick preset of the notebook's manifest (-p values win)"
    )
    r.add_argument("--list", action="store_true", help="list the notebook's parameters and exit")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr (only errors)")
    add_json_option(r, "the executed notebook and the outputs folder (with --list: the parameters)")
    for parser in (p, r):
        parser.add_argument(
            "--notebooks",
            type=Path,
            metavar="DIR",
            help="the jupytext notebooks NN_name.py of DIR instead of glu's own",
        )


def _notebooks_folder(args: argparse.Namespace) -> Path:
    """The folder of ``--notebooks`` (glu's own by default); NotebookError when it is not a folder."""
    from glu import paths
    from glu.run.reproduce import NotebookError

    folder = args.notebooks or paths.NOTEBOOKS_DIR
    if not folder.is_dir():
        raise NotebookError(f"--notebooks {folder}: no such folder")
    return folder


def _reproduce(args: argparse.Namespace) -> int:
    require_extra("notebooks", *NOTEBOOK_MODULES)
    if not args.no_site:
        require_extra("docs", *SITE_MODULES)
    from glu.run.reproduce import reproduce

    folder = _notebooks_folder(args)
    summary = reproduce(
        **chosen(args, "data", "quick", "out", "jobs", "only", "seed", "force"),
        site=not args.no_site,
        notebooks_dir=folder,
    )
    print(
        f"ran {len(summary['ran'])} notebooks in {summary['wall_time_s']:.1f} s ({summary['data_source']}); "
        f"the summary covers {len(summary['notebooks'])} notebooks, {len(summary['figures'])} figure files, "
        f"{len(summary['recordings'])} recordings"
    )
    for c in summary["comparison_with_reference"]:
        print(
            f"  {c['table']}: max |ours − {c['reference']}| = {c['max_abs_difference']:.3g} "
            f"over {c['rows']} numbers"
        )
    return 0


def _run(args: argparse.Namespace) -> int:
    require_extra("notebooks", *NOTEBOOK_MODULES)
    from glu.run.parameters import read_spec
    from glu.run.reproduce import NotebookError, list_notebooks, run_one

    folder = _notebooks_folder(args)
    if args.list:
        (src,) = list_notebooks([args.notebook], folder)[:1]
        spec = read_spec(src).values()
        if args.json:
            print(json_text([_parameter_json(p) for p in spec]))
            return 0
        for p in spec:
            print(p.describe())
        return 0
    names = [name for name, _ in args.parameter]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise NotebookError(f"-p {twice[0]} given more than once")
    executed, layout = run_one(
        args.notebook,
        dict(args.parameter),
        data=args.data,
        out=args.out,
        notebooks_dir=folder,
        quick=args.quick,
        progress=not args.quiet,
        **({"log": lambda line: None} if args.quiet else {}),
    )
    if args.json:
        print(json_text({"notebook": executed.stem, "executed": str(executed), "outputs": str(layout.root)}))
        return 0
    print(f"executed notebook: {executed}")
    print(f"outputs: {layout.root}")
    return 0


def _parameter_json(p) -> dict:  # type: ignore[no-untyped-def]
    """A notebook parameter for ``glu run --list --json``."""
    return {
        "name": p.name,
        "type": p.type,
        "default": p.default,
        "choices": list(p.choices) if p.choices else None,
        "range": list(p.range) if p.range else None,
        "help": p.help,
    }
