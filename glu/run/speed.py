"""The speed page's tables, written from the benchmarks' results — never typed by hand.

Every benchmark in ``benchmarks/`` writes ``benchmarks/results/NAME.json`` in one schema
(``benchmarks/timing.py``: the benchmark, what it measures, the command, the machine and its load, the date,
notes, and rows of glu's seconds against a reference's, with a target). :func:`render` turns those files into
the generated section of ``docs/speed.md`` (between :data:`BEGIN` and :data:`END`); ``glu readme`` writes it
and ``glu readme --check`` compares it, and a test checks that the page is what this module writes from the
files.

Example
-------
>>> print(fmt(0.0063), fmt(2.5), fmt(3.2e-5))
6.30 ms 2.50 s 32.0 µs
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from glu import paths
from glu.errors import DataError
from glu.run.generated import md_cell

_ROOT = paths.PROJECT_ROOT
RESULTS: Path | None = _ROOT / "benchmarks" / "results" if _ROOT is not None else None
"""The benchmarks' results in a checkout (None when glu is installed).

:meta hide-value:
"""
BEGIN = (
    "<!-- BEGIN benchmarks: written by `glu readme` from benchmarks/results/*.json; edit glu/run/speed.py -->"
)
"""The marker that opens the speed page's tables."""
END = "<!-- END benchmarks -->"
"""The marker that closes them."""
SCHEMA = 1
ORDER = (
    "reproduce",
    "bn",
    "networks",
    "hmm",
    "training",
    "kernels",
    "fast_paths",
    "corpus",
    "self_supervised",
)
"""The order of the sections (any other benchmark follows, by name)."""
KEYS = ("schema", "benchmark", "what", "command", "machine", "date", "notes", "rows")
ROW_KEYS = ("name", "what", "glu_s", "reference", "reference_s", "ratio", "target", "met")


def fmt(seconds: float) -> str:
    """Seconds in a readable unit."""
    if seconds >= 1:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.2f} ms"
    return f"{seconds * 1e6:.1f} µs"


def load_results(folder: str | os.PathLike | None = RESULTS) -> list[dict[str, Any]]:
    """Every benchmark's results in ``folder``, checked against the schema, in :data:`ORDER`."""
    if folder is None:
        raise DataError("glu is installed, not a source checkout: there are no benchmark results")
    docs = []
    for f in sorted(Path(folder).glob("*.json")):
        try:
            doc = json.loads(f.read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            raise DataError(f"{f.name}: not readable benchmark results ({e})") from None
        missing = [k for k in KEYS if not isinstance(doc, dict) or k not in doc]
        if missing or doc["schema"] != SCHEMA:
            raise DataError(
                f"{f.name}: not in the benchmarks' schema {SCHEMA} (missing {', '.join(missing)})"
            )
        bad = [i for i, r in enumerate(doc["rows"]) if set(ROW_KEYS) - set(r)]
        if bad:
            raise DataError(
                f"{f.name}: row {bad[0]} lacks {', '.join(sorted(set(ROW_KEYS) - set(doc['rows'][bad[0]])))}"
            )
        docs.append(doc)
    rank = {name: i for i, name in enumerate(ORDER)}
    return sorted(docs, key=lambda d: (rank.get(d["benchmark"], len(ORDER)), d["benchmark"]))


def _row(r: Mapping[str, Any]) -> str:
    name = md_cell(r["name"]) + (f" — *{md_cell(r['what'])}*" if r["what"] else "")
    reference = f"{md_cell(r['reference'])}: {fmt(r['reference_s'])}" if r["reference_s"] else "—"
    ratio = f"{r['ratio']:.1f}×" if r["ratio"] else "—"
    target = "—" if not r["target"] else md_cell(r["target"])
    if r["met"] is not None:
        target += ": met" if r["met"] else ": **missed**"
    return f"| {name} | {fmt(r['glu_s'])} | {reference} | {ratio} | {target} |"


def section(doc: Mapping[str, Any]) -> str:
    """One benchmark's part of the page: a heading, how and where it ran, its table and its notes."""
    lines = [
        f"## {doc['benchmark']}",
        "",
        f"{md_cell(doc['what'])[:1].upper()}{md_cell(doc['what'])[1:]}: `{doc['command']}`, {doc['date']}; "
        f"{md_cell(doc['machine'])}.",
        "",
        "| measurement | glu | reference | reference / glu | target |",
        "|---|---|---|---|---|",
        *(_row(r) for r in doc["rows"]),
    ]
    if doc["notes"]:
        lines += ["", *(f"* {md_cell(n)}" for n in doc["notes"])]
    return "\n".join(lines)


def render(docs: Sequence[Mapping[str, Any]]) -> str:
    """The generated section of the speed page (without the markers)."""
    return "\n\n".join(section(d) for d in docs)
