"""Reading a BIF file is linear in its length: import time of generated BIF files of 10,000 to 100,000 lines.

Run on demand (not a test)::

    python benchmarks/bench_bif_import.py [--repeats N]

Two shapes of file, each at several lengths: a **chain** of binary variables (one variable block and one
probability block of one row per parent value per node), and **one wide parent** whose values are listed
and whose child has one row per value (the shape that made the earlier regular-expression reader
quadratic: each row looked its value up in a list); and **unclosed** variable blocks (a file cut or mangled:
the earlier reader's pattern for a block searched to the end of the file from every ``variable``, 13.7 s for
8,000 lines, about 55 s for 16,000; glu now refuses it at the first block, after reading it once). For each, the best of N calls of
:func:`glu.bn.exchange.from_bif` on the text (the file is generated in memory), and seconds per 10,000
lines: a linear reader keeps that ratio flat. Results go to ``benchmarks/results/bif_import.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

from glu.bn.exchange import from_bif
from glu.errors import ModelError

RESULTS = Path(__file__).parent / "results" / "bif_import.json"


def chain_bif(lines: int) -> str:
    """A chain X0 → X1 → … of binary variables, about ``lines`` lines long (7 lines a node)."""
    n = max(2, lines // 7)
    out = ["network chain {", "}"]
    for i in range(n):
        out += [f"variable X{i} {{", "  type discrete [ 2 ] { a, b };", "}"]
    out += ["probability ( X0 ) {", "  table 0.4, 0.6;", "}"]
    for i in range(1, n):
        out += [f"probability ( X{i} | X{i - 1} ) {{", "  (a) 0.3, 0.7;", "  (b) 0.9, 0.1;", "}"]
    return "\n".join(out) + "\n"


def wide_bif(lines: int) -> str:
    """A parent with ``k`` values, one per line, and a binary child with one row per value (≈ 2k lines)."""
    k = max(2, (lines - 12) // 2)
    out = ["network wide {", "}", "variable P {", f"  type discrete [ {k} ] {{"]
    out += [f"    v{j}," for j in range(k - 1)] + [f"    v{k - 1}", "  };", "}"]
    out += ["variable C {", "  type discrete [ 2 ] { a, b };", "}"]
    out += ["probability ( P ) {", "  table " + ", ".join(["1"] + ["0"] * (k - 1)) + ";", "}"]
    out += ["probability ( C | P ) {"] + [f"  (v{j}) 0.25, 0.75;" for j in range(k)] + ["}"]
    return "\n".join(out) + "\n"


def unclosed_bif(lines: int) -> str:
    """Variable blocks that are never closed (the file is refused; how fast is the point)."""
    out = []
    for i in range(max(1, lines // 2)):
        out += [f"variable X{i} {{", "  type discrete [ 2 ] { a, b };"]
    return "\n".join(out) + "\n"


def _read(text: str) -> None:
    try:
        from_bif(text)
    except ModelError:
        pass


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    rows = []
    for shape, make in (("chain", chain_bif), ("wide", wide_bif), ("unclosed", unclosed_bif)):
        for target in (10_000, 25_000, 50_000, 100_000):
            text = make(target)
            n_lines = text.count("\n")
            times = []
            for _ in range(args.repeats):
                t = time.perf_counter()
                _read(text)
                times.append(time.perf_counter() - t)
            best = min(times)
            rows.append(
                {
                    "shape": shape,
                    "lines": n_lines,
                    "seconds": round(best, 3),
                    "s_per_10k_lines": round(best / n_lines * 1e4, 4),
                }
            )
            print(
                f"{shape:6s} {n_lines:8,d} lines  {best:7.3f} s  ({best / n_lines * 1e4:.3f} s per 10,000 lines)"
            )
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(
        json.dumps(
            {
                "machine": platform.machine(),
                "python": platform.python_version(),
                "repeats": args.repeats,
                "results": rows,
            },
            indent=1,
        )
        + "\n"
    )
    print(f"wrote {RESULTS.name}")


if __name__ == "__main__":
    main()
