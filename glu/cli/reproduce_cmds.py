"""``glu reproduce``: run every notebook headless and regenerate all figures, recordings and results."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``reproduce`` command."""
    p = sub.add_parser(
        "reproduce", help="run every notebook: figures, recordings, results summary", description=__doc__
    )
    p.add_argument(
        "--data", help="data folder, or 'synthetic' (default: $GLU_DATA_DIR, data/real, else synthetic)"
    )
    p.add_argument("--quick", action="store_true", help="small, fast runs (as the tests do)")
    p.add_argument("--out", type=Path, help="write figures/, recordings/, results/, notebooks/ here instead")
    p.add_argument("-j", "--jobs", type=int, default=2, help="notebooks run in parallel (default 2)")
    p.add_argument(
        "--only", nargs="+", metavar="NOTEBOOK", help="run only these notebooks (names or numbers)"
    )
    p.add_argument("--seed", type=int, default=0, help="seed passed to every notebook (default 0)")
    p.set_defaults(func=_reproduce)


def _reproduce(args: argparse.Namespace) -> int:
    from glu.reproduce import reproduce

    summary = reproduce(
        data=args.data, quick=args.quick, out=args.out, jobs=args.jobs, only=args.only, seed=args.seed
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
