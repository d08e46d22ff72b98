"""Wall time of the whole collection: `glu reproduce` on 2 cores, notebook by notebook.

Run on demand (not a test)::

    python benchmarks/bench_reproduce.py [--data DIR] [--jobs 2] [--repeats 1]

Runs every notebook headless into a temporary folder (nothing is published into the project), as
`glu reproduce -o TMP` does, and prints and writes (``benchmarks/results/reproduce.json``) the total wall
time and each notebook's time. The total is the summary's ``wall_time_s``: running and publishing the
notebooks; the documentation site, built after it (``glu.run.site``, logged with its own time), is not
included. The folder is
new, so the notebooks start in the order of the project's last run (``results/summary.json``), else of
the times the notebooks declare (``glu: expected_seconds`` in their headers), longest first. The goal
(issue #22, with notebooks 11 and 12 at their default sizes): the whole collection on the real data in at
most 60 s on 2 cores.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile

from timing import report, row


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="data folder (default: as glu reproduce finds it)")
    ap.add_argument("--jobs", type=int, default=2, help="notebooks at once (default 2)")
    ap.add_argument("--repeats", type=int, default=1, help="whole runs (default 1)")
    args = ap.parse_args(argv)
    from glu.data import resolve_data
    from glu.run.reproduce import reproduce

    walls, per_notebook = [], {}
    for _ in range(args.repeats):
        with tempfile.TemporaryDirectory(prefix="glu-bench-") as out:
            summary = reproduce(
                data=args.data, out=out, jobs=args.jobs, log=lambda _s: None, progress=False, site=False
            )
        walls.append(summary["wall_time_s"])
        for nb in summary["notebooks"]:
            per_notebook.setdefault(nb["name"], []).append(nb["seconds"])
    wall = statistics.median(walls)
    rows = [
        row(
            f"glu reproduce, every notebook, {args.jobs} at a time, the site not included (median of "
            f"{args.repeats})",
            wall,
            target="≤ 60 s",
            met=wall <= 60,
        )
    ]
    rows += [row(f"notebook {name}", statistics.median(secs)) for name, secs in per_notebook.items()]
    busy = sum(statistics.median(secs) for secs in per_notebook.values())
    report(
        "reproduce",
        "the whole collection: glu reproduce, notebook by notebook (wall time)",
        rows,
        notes=[
            f"{resolve_data(args.data).describe()}, -j {args.jobs}",
            f"runs: {', '.join(f'{w:.1f}' for w in walls)} s; the notebooks summed {busy:.1f} s",
        ],
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
