"""Notebook prose quotes no computed number: results are printed by code cells (issue #10).

Markdown cells may name sections, figures, counts of the design (notebook numbers, "GLU 2017") and the
papers' own numbers, listed here with where they come from; a decimal number or an approximation
anywhere else is a result typed by hand.
"""

from __future__ import annotations

import re

import jupytext
import pytest

from glu.run.reproduce import list_notebooks

PAPERS_NUMBERS = {
    "0.81": "TCDS 2020: tap wins only when p_HMM(tap) > 0.81 (notebook 06 compares glu's threshold)"
}
RESULT_LIKE = re.compile(r"≈\s*\d|(?<![§\w.])\d+\.\d+|\d+(?:\.\d+)?\s?%")


@pytest.mark.parametrize("path", list_notebooks(), ids=lambda p: p.stem)
def test_markdown_cells_quote_no_computed_number(path):
    found = []
    for cell in jupytext.read(path).cells:
        if cell.cell_type != "markdown":
            continue
        for m in RESULT_LIKE.finditer(cell.source):
            if m.group(0) not in PAPERS_NUMBERS:
                found.append(f"{m.group(0)!r} in “…{cell.source[max(0, m.start() - 40) : m.end() + 20]}…”")
    assert not found, f"{path.name}: numbers typed by hand in prose (print them from code): {found}"
