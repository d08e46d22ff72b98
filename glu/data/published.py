"""The numbers the papers printed, typed once into a reference file that names where each was read.

``glu/resources/published/tcds2020.json`` holds what TCDS 2020 published and glu reproduces: the sentence
lists of Table II and Fig. 7 (sentences and scores as printed), the four Fig. 8 sentences, the Fig. 7
conjunction bars, and the effect-anticipation figure (Fig. 5): the three per-frame log-likelihood curves,
the final p_comb(ObjVel) bars and the captions. Every entry says where it was read (file and lines of the
authors' LaTeX at a pinned commit, or how a figure's EPS path coordinates were converted, with the
resulting resolution). Nothing computes these numbers; tests and notebooks compare glu's against them.

:func:`num2str` formats a number as the originals' MATLAB printed it, so scores can be compared "to the last
printed digit".
"""

from __future__ import annotations

import json
import math
from functools import cache
from typing import Any

from glu import paths
from glu.errors import DataError

PUBLISHED_DIR = paths.RESOURCES_DIR / "published"
"""The papers' printed numbers, shipped with the package.

:meta hide-value:
"""
TCDS2020 = "tcds2020"
"""TCDS 2020, *Beyond the Self* (the journal follow-up)."""


@cache
def _text(name: str) -> str:
    path = PUBLISHED_DIR / f"{name}.json"
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        have = sorted(p.stem for p in PUBLISHED_DIR.glob("*.json"))
        raise DataError(f"no published numbers named {name!r}; there are: {', '.join(have)}") from None


def published(name: str = TCDS2020) -> dict[str, Any]:
    """The published numbers of a paper (``glu/resources/published/<name>.json``; a fresh copy each call).

    Returns
    -------
    dict with ``paper``, ``read_from`` and, for TCDS 2020, ``sentences`` (``table_ii``, ``fig7a``,
    ``fig7b``, ``fig8``), ``conjunctions`` and ``anticipation`` (``sphere``, ``box``).
    """
    return json.loads(_text(name))


def num2str(x: float) -> str:
    """``x`` as MATLAB's ``num2str`` prints a scalar: ``max(digits before the point, 1) + 4`` significant
    digits.

    That is 5 significant digits below 1 in magnitude, trailing zeros dropped (how the originals printed
    every sentence score).

    >>> num2str(-0.543222470554526), num2str(-0.5499996), num2str(3.14159265), num2str(123.4567)
    ('-0.54322', '-0.55', '3.1416', '123.4567')
    """
    x = float(x)
    if not math.isfinite(x):
        return {math.inf: "Inf", -math.inf: "-Inf"}.get(x, "NaN")
    if x == int(x):
        return str(int(x))
    digits = max(math.floor(math.log10(abs(x))) + 1, 1) + 4
    return f"{x:.{digits}g}"
