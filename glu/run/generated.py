"""Sections of the project's Markdown pages written by code between markers, never typed by hand.

A generated section sits between a ``BEGIN`` and an ``END`` HTML comment (invisible on GitHub and in the
docs). :func:`section` reads one, :func:`replace_section` writes one atomically. This module also writes
the README's story table, one row per notebook, from the manifests in the notebooks' headers
(:mod:`glu.run.manifest`: ``about`` and ``figures``), so the table cannot disagree with the notebooks.
The README's results section is :mod:`glu.run.readme`'s; the speed page's tables are
:mod:`glu.run.speed`'s. ``glu readme`` writes them all; ``glu readme --check`` says which differ.

Example
-------
>>> from glu.run.manifest import Manifest
>>> print(story_table([Manifest("01_x", "what it shows", figures=("a", "b"))]))
| notebook | what it shows | figures (`figures/`) |
|---|---|---|
| `01_x` | what it shows | `a`, `b` |
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from glu import paths
from glu.errors import DataError
from glu.files import atomic_write_text
from glu.run.manifest import Manifest, read_manifest

STORY_BEGIN = (
    "<!-- BEGIN story: written by `glu readme` from the notebooks' manifests; edit their headers -->"
)
STORY_END = "<!-- END story -->"


def section(text: str, begin: str, end: str, where: str = "README.md") -> str:
    """The text between ``begin`` and ``end`` (stripped); :class:`DataError` unless each occurs once."""
    if text.count(begin) != 1 or text.count(end) != 1 or text.index(begin) > text.index(end):
        raise DataError(f"{where}: expected one generated section between the markers {begin!r} and {end!r}")
    return text.split(begin, 1)[1].split(end, 1)[0].strip()


def replace_section(path: str | os.PathLike, begin: str, end: str, new: str) -> bool:
    """Write ``new`` between the markers of the page at ``path`` (atomically); True if it changed."""
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    if section(text, begin, end, path.name) == new.strip():
        return False
    head, rest = text.split(begin, 1)
    tail = rest.split(end, 1)[1]
    atomic_write_text(path, f"{head}{begin}\n{new.strip()}\n{end}{tail}")
    return True


def manifests(folder: str | os.PathLike = paths.NOTEBOOKS_DIR) -> list[Manifest]:
    """The manifests of the story's notebooks (``NN_name.py``), in order."""
    found = sorted(Path(folder).glob("[0-9][0-9]_*.py"))
    if not found:
        raise DataError(f"no notebooks NN_name.py in {folder}")
    return [read_manifest(p) for p in found]


def md_cell(text: object) -> str:
    """Text for a cell of a Markdown table: on one line, its whitespace squeezed, its pipes escaped."""
    return " ".join(str(text).split()).replace("|", "\\|")


def story_table(notebooks: Sequence[Manifest]) -> str:
    """The story table: each notebook, what it shows (its ``about``) and the figures it draws."""
    rows = ["| notebook | what it shows | figures (`figures/`) |", "|---|---|---|"]
    for m in notebooks:
        figures = ", ".join(f"`{f}`" for f in m.figures) or "—"
        rows.append(f"| `{m.notebook}` | {md_cell(m.about)} | {figures} |")
    return "\n".join(rows)
