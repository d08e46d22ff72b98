"""Reading a BIF file is linear in its length: import time of generated BIF files of 10,000 to 100,000 lines.

Run on demand (not a test)::

    python benchmarks/bench_bif_import.py [--repeats N]

Two shapes of file, each at several lengths: a **chain** of binary variables (one variable block and one
probability block of one row per parent value per node), and **one wide parent** whose values are listed
and whose child has one row per value (the shape that made the earlier regular-expression reader
quadratic: each row looked its value up in a list); and **unclosed** variable blocks (a file cut or mangled:
the earlier reader's pattern for a block searched to the end of the file from every ``variable``, 13.7 s for
8,000 lines, about 55 s for 16,000; glu now refuses it at the first block, after reading it once). For each,
the best of N calls of
:func:`glu.bn.exchange.from_bif` on the text (the file is generated in memory), and seconds per 10,000
lines: a linear reader keeps that ratio flat. Results go to ``benchmarks/results/bif_import.json``
(``timing.report``).
"""

from __future__ import annotations

import argparse
import time

from timing import report, row

from glu.bn.exchange import from_bif
from glu.errors import ModelError


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
        first = None  # (lines, seconds) of the shortest file: a linear reader scales it by the length
        for target in (10_000, 25_000, 50_000, 100_000):
            text = make(target)
            n_lines = text.count("\n")
            times = []
            for _ in range(args.repeats):
                t = time.perf_counter()
                _read(text)
                times.append(time.perf_counter() - t)
            best = min(times)
            first = first or (n_lines, best)
            per_100k = best / n_lines * 1e5
            rows.append(
                row(
                    f"{shape}: {n_lines:,} lines",
                    best,
                    reference=f"the {first[0]:,}-line file's time × length (a linear reader)",
                    reference_s=first[1] * n_lines / first[0],
                    target="≤ 10 s per 100,000 lines",
                    met=per_100k <= 10.0,
                    what=SHAPES[shape],
                )
            )
    report(
        "bif_import",
        "Reading BIF files of 10,000 to 100,000 lines (glu.bn.exchange.from_bif, best of "
        f"{args.repeats}): a ratio near 1 at every length is a linear reader; a quadratic one falls as "
        "1/length",
        rows,
        notes=["unclosed: a cut or mangled file, refused at its first block after one pass"],
    )


SHAPES = {
    "chain": "a chain of binary variables, 7 lines a node",
    "wide": "one parent with one value per line, and a binary child with one row per value",
    "unclosed": "variable blocks never closed (the file is refused)",
}
"""What each shape of file is (the module docstring says why)."""


if __name__ == "__main__":
    main()
