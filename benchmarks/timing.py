"""What the benchmarks share: timing a call, and one schema for their results.

The benchmarks run as scripts (``from timing import median_time, row, report``). Each ends with
:func:`report`, which prints its table and writes ``benchmarks/results/NAME.json``::

    {"schema": 1, "benchmark": NAME, "what": ..., "command": "python benchmarks/bench_NAME.py ...",
     "machine": "x86_64, 2 cores, Python 3.11, NumPy 2.4; load average 1.2 at the start", "date":
     "2026-11-27", "notes": [...], "rows": [ROW, ...]}

and each ``ROW`` (:func:`row`) is ``{"name", "what", "glu_s", "reference", "reference_s", "ratio", "target",
"met"}``: glu's seconds, the reference's name and seconds (or null), ``ratio`` = reference / glu, a target in
words and whether it was met (null when there is none). ``docs/speed.md`` is written from these files
(``glu readme``, :mod:`glu.run.speed`, which checks the schema), never typed by hand.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from glu.run.speed import SCHEMA, fmt  # the page is written from these files by glu.run.speed

RESULTS = Path(__file__).resolve().parent / "results"


def calls_lasting(fn: Callable[[], object], seconds: float = 0.2) -> int:
    """How many calls of ``fn`` last at least ``seconds`` together (1, 10, 100, … then doubling)."""
    number = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        t = time.perf_counter() - t0
        if t >= seconds:
            return number
        number *= 2 if t > seconds / 10 else 10


def median_time(fn: Callable[[], object], repeats: int, number: int = 1) -> float:
    """Median over ``repeats`` of the mean time of ``number`` calls of ``fn``, in seconds."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return statistics.median(times)


def row(
    name: str,
    glu_s: float,
    reference: str | None = None,
    reference_s: float | None = None,
    target: str | None = None,
    met: bool | None = None,
    what: str = "",
) -> dict[str, Any]:
    """One measurement in the results' schema (``ratio`` = reference / glu, when there is a reference)."""
    ratio = reference_s / glu_s if reference_s and glu_s else None
    return {
        "name": name,
        "what": what,
        "glu_s": float(glu_s),
        "reference": reference,
        "reference_s": None if reference_s is None else float(reference_s),
        "ratio": ratio,
        "target": target,
        "met": None if met is None else bool(met),
    }


def machine() -> str:
    """The machine a benchmark ran on, and how loaded it was at the start."""
    import numpy

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
        f"{platform.python_version()}, NumPy {numpy.__version__}; load average {load:.1f} at the start"
        + (" (a shared machine: preliminary)" if load > 0.5 else "")
    )


def report(
    benchmark: str,
    what: str,
    rows: Sequence[dict[str, Any]],
    notes: Sequence[str] = (),
    out: Path | None = None,
    machine_note: str | None = None,
) -> Path:
    """Print the table and write the results as JSON (default ``benchmarks/results/BENCHMARK.json``)."""
    note = machine_note or machine()
    print(f"# {what}\n# {note}")
    for n in notes:
        print(f"# {n}")
    print(f"{'measurement':60s} {'glu':>10s} {'reference':>10s} {'ratio':>9s}  target")
    for r in rows:
        ref = fmt(r["reference_s"]) if r["reference_s"] else "-"
        ratio = f"{r['ratio']:.1f}×" if r["ratio"] else "-"
        ok = "" if r["met"] is None else ("met" if r["met"] else "MISSED")
        print(f"{r['name'][:60]:60s} {fmt(r['glu_s']):>10s} {ref:>10s} {ratio:>9s}  {r['target'] or ''} {ok}")
    args = " ".join(
        "PATH" if os.path.isabs(a.split("=")[-1]) else a for a in sys.argv[1:]
    )  # no machine paths
    doc = {
        "schema": SCHEMA,
        "benchmark": benchmark,
        "what": what,
        "command": f"python benchmarks/{Path(sys.argv[0]).name}" + (f" {args}" if args else ""),
        "machine": note,
        "date": datetime.date.today().isoformat(),
        "notes": list(notes),
        "rows": list(rows),
    }
    out = out or RESULTS / f"{benchmark}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".partial")
    tmp.write_text(json.dumps(doc, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    tmp.replace(out)
    print(f"wrote {out.relative_to(out.parents[2]) if len(out.parents) > 2 else out}")
    return out
