"""``glu reproduce`` runs every notebook headless and publishes all figures, recordings and results;
``glu run`` runs one notebook with other parameters, into its scratch folder."""

from __future__ import annotations

import argparse
from pathlib import Path

from glu.cli.common import DATA_HELP, positive_int, require_extra, seed

NOTEBOOK_MODULES = ("papermill", "jupytext", "ipykernel", "nbconvert", "rerun")
"""What running the notebooks needs: the extra ``glu[notebooks]``."""
SITE_MODULES = ("sphinx", "myst_nb", "pydata_sphinx_theme")
"""What building the documentation site needs: the extra ``glu[docs]`` (in ``glu[notebooks]``)."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``reproduce`` and ``run`` commands."""
    p = sub.add_parser(
        "reproduce",
        help="run every notebook: figures, recordings, results summary, documentation site",
        description="Run every notebook headless; publish their outputs only when all succeed.",
    )
    p.add_argument("--data", help=DATA_HELP)
    p.add_argument("--quick", action="store_true", help="small, fast runs (as the tests do)")
    p.add_argument(
        "--out",
        type=Path,
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
        "--notebooks",
        type=Path,
        metavar="DIR",
        help="run the jupytext notebooks NN_name.py in DIR instead of glu's own",
    )
    p.set_defaults(func=_reproduce)

    r = sub.add_parser(
        "run",
        help="run one notebook headless with other parameters (into its scratch folder)",
        description=(
            "Run one notebook headless. Parameters are checked against the notebook's parameters cell "
            "before anything executes. Outputs go to build/scratch/NOTEBOOK/ unless --out is given; "
            "only `glu reproduce` publishes into figures/, results/, recordings/, models/."
        ),
    )
    r.add_argument("notebook", help="the notebook's name or number (e.g. 08_tcds_figures or 8)")
    r.add_argument(
        "-p",
        "--parameter",
        nargs=2,
        action="append",
        default=[],
        metavar=("NAME", "VALUE"),
        help="set a parameter (repeatable); `glu run NOTEBOOK --list` shows them",
    )
    r.add_argument("--data", help=DATA_HELP)
    r.add_argument("--out", type=Path, help="output folder (default: build/scratch/NOTEBOOK/)")
    r.add_argument(
        "--quick", action="store_true", help="the quick preset of the notebook's manifest (-p values win)"
    )
    r.add_argument("--list", action="store_true", help="list the notebook's parameters and exit")
    r.set_defaults(func=_run)


def _reproduce(args: argparse.Namespace) -> int:
    from glu import paths

    require_extra("notebooks", *NOTEBOOK_MODULES)
    if not args.no_site:
        require_extra("docs", *SITE_MODULES)
    from glu.run.reproduce import NotebookError, reproduce

    folder = args.notebooks or paths.NOTEBOOKS_DIR
    if not folder.is_dir():
        raise NotebookError(f"--notebooks {folder}: no such folder")
    summary = reproduce(
        data=args.data,
        quick=args.quick,
        out=args.out,
        jobs=args.jobs,
        only=args.only,
        seed=args.seed,
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
            f"  {c['table']}: max |ours − {c['reference']}| = {c['max_abs_difference']:.3g} over {c['rows']} numbers"
        )
    return 0


def _run(args: argparse.Namespace) -> int:
    require_extra("notebooks", *NOTEBOOK_MODULES)
    from glu.run.parameters import read_spec
    from glu.run.reproduce import NotebookError, list_notebooks, run_one

    if args.list:
        (src,) = list_notebooks([args.notebook])[:1]
        for p in read_spec(src).values():
            print(p.describe())
        return 0
    names = [name for name, _ in args.parameter]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise NotebookError(f"-p {twice[0]} given more than once")
    executed, layout = run_one(
        args.notebook, dict(args.parameter), data=args.data, out=args.out, quick=args.quick
    )
    print(f"executed notebook: {executed}")
    print(f"outputs: {layout.root}")
    return 0
