"""Rows of conditional probability tables: naming a row, checking that rows are distributions, rescaling.

A CPT of shape ``(*parent cardinalities, cardinality)`` has one row per parent configuration; a row is named
``P(node | parent=value, …)`` in every message, so that a user can find it in the file.

>>> values = {"A": ("a0", "a1"), "B": ("b0", "b1")}
>>> cpt = np.array([[0.5, 0.5], [0.25, 0.75001]])
>>> fixed, report = normalise_rows(values, {"A": (), "B": ("A",)},
...                                {"A": np.array([0.5, 0.5]), "B": cpt}, 1e-4)
>>> report["rows"], report["at"], round(float(fixed["B"][1].sum()), 12)
(1, 'P(B | A=a1)', 1.0)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from glu.bn.model import ROW_TOL
from glu.errors import ModelError

RENORMALISE_DEFAULT = 1e-3
"""The tolerance of ``glu bn import --renormalise`` given without a value."""


def row_name(
    node: str, index: Sequence[int], values: Mapping[str, Sequence[str]], parents: Sequence[str]
) -> str:
    """``P(node | A=a, B=b)``: the row of ``node``'s table at parent value indices ``index``."""
    if not parents:
        return f"P({node})"
    config = ", ".join(f"{p}={values[p][int(i)]}" for p, i in zip(parents, index, strict=True))
    return f"P({node} | {config})"


def check_tolerance(value: Any) -> float:
    """``value`` as a row-sum tolerance, a number in [0, 1); :class:`ModelError` otherwise."""
    try:
        tol = float(value)
    except (TypeError, ValueError):
        tol = float("nan")
    if not 0 <= tol < 1:
        raise ModelError(f"renormalise={value!r}: a tolerance is a number in [0, 1), e.g. 1e-4")
    return tol


def check_rows(
    node: str,
    cpt: np.ndarray,
    values: Mapping[str, Sequence[str]],
    parents: Sequence[str],
    tol: float,
    where: str,
) -> None:
    """:class:`ModelError` naming the first row of ``cpt`` that is not a distribution within ``tol``.

    ``cpt``, shape ``(*parent cardinalities, cardinality)``, its axes in the order of ``parents``. The
    message gives the row (:func:`row_name`), its sum, how many other rows are off, and the
    ``--renormalise`` tolerance that would accept it when it is close to 1.
    """
    sums = cpt.sum(axis=-1)
    bad_entries = ~np.isfinite(cpt) | (cpt < 0)
    bad = bad_entries.any(axis=-1) | ~(np.abs(sums - 1) <= tol)
    if not bad.any():
        return
    k = tuple(int(i) for i in np.argwhere(bad)[0])
    row = row_name(node, k, values, parents)
    if bad_entries[k].any():
        raise ModelError(
            f"{where}: the row {row} has an entry that is negative or not a number: {cpt[k].tolist()}"
        )
    hint = ""
    if abs(sums[k] - 1) < 0.1:
        suggest = float(f"{10 ** np.ceil(np.log10(abs(sums[k] - 1))):.0e}")
        hint = f"; to rescale such rows, give --renormalise {suggest:g} (in Python: renormalise={suggest:g})"
    more = int(bad.sum()) - 1
    raise ModelError(
        f"{where}: the row {row} sums to {sums[k]:.10g}, not 1 (|1 − sum| = {abs(sums[k] - 1):.2g}, "
        f"tolerance {tol:g}){f' — and {more} more rows' if more else ''}{hint}"
    )


def normalise_rows(
    values: Mapping[str, Sequence[str]],
    parents: Mapping[str, Sequence[str]],
    cpts: Mapping[str, np.ndarray],
    tol: float,
    where: str = "model",
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Check every row (:func:`check_rows`) and rescale those off 1 by more than ``ROW_TOL`` to sum to 1.

    ``cpts``: node → table, shape ``(*parent cardinalities, cardinality)``, axes in the order of
    ``parents[node]``. Returns (cpts, report): the tables, of the same shapes, and — when a row was
    rescaled — ``{"rows": how many, "largest_deviation": the largest |1 − sum|, "at": that row's name,
    "tolerance": tol}``, else ``{}``.
    """
    tol = check_tolerance(tol)
    out, rescaled, worst = {}, 0, (0.0, "")
    for n, c in cpts.items():
        check_rows(n, c, values, parents[n], tol, where)
        sums = c.sum(axis=-1, keepdims=True)
        off = np.abs(sums - 1) > ROW_TOL  # only rows another tool rounded
        out[n] = np.where(off, c / sums, c) if off.any() else c
        if off.any():
            rescaled += int(off.sum())
            dev = np.abs(sums - 1)[..., 0]
            k = np.unravel_index(int(np.argmax(dev)), dev.shape)
            if dev[k] > worst[0]:
                worst = (float(dev[k]), row_name(n, k, values, parents[n]))
    report = {"rows": rescaled, "largest_deviation": worst[0], "at": worst[1], "tolerance": tol}
    return out, report if rescaled else {}
