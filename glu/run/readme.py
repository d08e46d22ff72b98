"""The README's results section, written from ``results/summary.json`` — never typed by hand.

``glu readme`` renders :data:`TEMPLATE` — a first paragraph, then each study's bullets, written by the study
(:func:`glu.studies.readme_parts`) — with the numbers of a full run on the real data (``make reproduce
DATA=…``; :func:`values` asks each study for its slots) and writes it between :data:`BEGIN` and
:data:`END` in ``README.md``; ``glu readme --check`` says whether the README is up to date. The only
numbers in the template itself are the papers' own, quoted as such. A test checks that the README's
section is this template with a number in every slot and nowhere else (:func:`section_pattern`).
"""

from __future__ import annotations

import json
import os
import re
import string
import textwrap
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from glu import paths
from glu.errors import DataError
from glu.run import generated
from glu.studies import readme_parts

_ROOT = paths.PROJECT_ROOT
README: Path | None = _ROOT / "README.md" if _ROOT is not None else None
"""The checkout's README (None when glu is installed: then give the files explicitly).

:meta hide-value:
"""
SUMMARY: Path | None = _ROOT / "results" / "summary.json" if _ROOT is not None else None
"""The checkout's last run's summary (None when glu is installed).

:meta hide-value:
"""
BEGIN = (
    "<!-- BEGIN results: written by `glu readme` from results/summary.json; edit each study's readme.py, "
    "not here -->"
)
"""The marker that opens the README's results section."""
END = "<!-- END results -->"
"""The marker that closes it."""

INTRO = """\
Every number below comes from `make reproduce` on the real data (the tables of its {notebooks} notebooks): \
`glu readme` writes this section from `results/summary.json`.
"""
"""The section's first paragraph; each study's bullets follow (:func:`glu.studies.readme_parts`)."""
PARTS = readme_parts()
TEMPLATE = INTRO + "\n" + "\n".join(part.TEMPLATE for part in PARTS)
"""The results section, with ``{name:format}`` slots filled by :func:`values`."""
REQUIRED: tuple[str, ...] = tuple(dict.fromkeys(t for part in PARTS for t in part.REQUIRED))
"""The result tables the section is written from."""


def load_summary(path: str | os.PathLike = SUMMARY) -> dict[str, Any]:
    """The summary of ``glu reproduce``; :class:`DataError` if it is missing or not a full run on the real
    data."""
    path = Path(path)
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataError(f"{path}: no summary; run `make reproduce DATA=<the real data>` first") from None
    except (OSError, ValueError) as e:  # ValueError: not UTF-8, not JSON
        raise DataError(f"{path}: not a readable summary ({e})") from None
    if not isinstance(summary, dict):
        raise DataError(f"{path}: not a summary of `glu reproduce` (expected a JSON object)")
    if summary.get("quick") or not str(summary.get("data_source", "")).startswith("real data"):
        raise DataError(
            f"{path}: the README quotes a full run on the real data, not this one "
            f"({summary.get('data_source')}, quick={summary.get('quick')})"
        )
    missing = [t for t in REQUIRED if t not in summary.get("tables", {})]
    if missing:
        raise DataError(f"{path}: the summary lacks {', '.join(missing)}; run every notebook")
    return summary


def tables(summary: Mapping[str, Any]) -> dict[str, tuple[pd.DataFrame, dict[str, Any]]]:
    """The summary's tables: name → (its rows as a frame, its meta)."""
    return {name: (pd.DataFrame(t["rows"]), t["meta"]) for name, t in summary["tables"].items()}


def values(summary: Mapping[str, Any]) -> dict[str, Any]:
    """Every slot of :data:`TEMPLATE`, read from the summary's tables (see :data:`REQUIRED`) by each study;
    a slot a study fills with a list of sentences becomes one bullet each, under the study's bullet."""
    v: dict[str, Any] = {"notebooks": len(summary["notebooks"])}
    t = tables(summary)
    for part in PARTS:
        for slot, value in part.values(t).items():
            if isinstance(value, list):  # sentences: bullets under the study's bullet
                value = "\n".join(f"  * {s}" for s in value)
            if slot in v and v[slot] != value:
                raise DataError(
                    f"two studies fill the README slot {slot!r} differently ({v[slot]!r}, {value!r})"
                )
            v[slot] = value
    return v


WIDTH = 110
"""README lines are wrapped at this width."""


def _wrap(text: str) -> str:
    """Each paragraph or bullet of ``text`` wrapped at :data:`WIDTH`, bullets indented as markdown wants."""
    out = []
    for line in text.splitlines():
        bullet = re.match(r"( *)(\* )?", line)
        indent = bullet.group(1) + ("  " if bullet.group(2) else "")
        out.append(
            textwrap.fill(
                line, WIDTH, subsequent_indent=indent, break_on_hyphens=False, break_long_words=False
            )
        )
    return "\n".join(out)


def render(summary: Mapping[str, Any]) -> str:
    """The results section (without the markers) for a summary, wrapped at :data:`WIDTH`."""
    return _wrap(TEMPLATE.format(**values(summary)))


NUMBER = r"[-+−]?\d[\d,]*(?:\.\d+)?(?:e[-+]?\d+)?"


def _squeeze(text: str) -> str:
    return re.sub(r"\s+", " ", text).strip()


def section_pattern() -> re.Pattern[str]:
    """A regular expression matching :data:`TEMPLATE` with any number (or, for text slots, any text) in each
    slot.

    It matches the section with its whitespace squeezed to single spaces (:func:`matches_template`).
    """
    out = []
    for literal, field, spec, _ in string.Formatter().parse(_squeeze(TEMPLATE)):
        out.append(re.escape(literal))
        if field is not None:
            out.append(f"(?:{NUMBER})" if spec else ".*?")
    return re.compile("".join(out))


def matches_template(section: str) -> bool:
    """True when ``section`` is :data:`TEMPLATE` with a number in every numeric slot, whatever the line
    breaks."""
    return section_pattern().fullmatch(_squeeze(section)) is not None


def readme_section(text: str) -> str:
    """The text between :data:`BEGIN` and :data:`END` in a README (stripped); DataError without exactly
    one."""
    return generated.section(text, BEGIN, END)


def update_readme(summary: Mapping[str, Any], path: str | os.PathLike = README) -> bool:
    """Write the rendered section into the README (atomically); True if it changed."""
    return generated.replace_section(path, BEGIN, END, render(summary))
