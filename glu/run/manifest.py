"""What each notebook declares about itself: the one place its outputs, quick preset and time are written.

Every notebook's jupytext header carries a ``glu`` block (kept by jupytext and by saves from JupyterLab)::

    # jupyter:
    #   glu:
    #     about: hand trajectories, tracking gaps and outliers, automatic segmentation into repetitions
    #     expected_seconds: 4
    #     figures:
    #     - gesture_segmentation
    #     tables:
    #     - gesture_segmentation
    #     quick:
    #       n_per_action: 6

* ``about`` — what the notebook shows, one line (the README's story table);
* ``figures``, ``tables``, ``recordings``, ``models`` — the names of what it writes (``figures/NAME.png``
  and ``.svg``, ``results/NAME.csv`` and ``.json``, ``recordings/NAME.rrd``, ``models/NAME``);
* ``real_only`` — those of the names above that only the real data produces (the original models'
  figures, say);
* ``quick`` — the parameter values of a quick run (``glu reproduce --quick``, the tests): small, fast,
  every figure still drawn;
* ``expected_seconds`` — a full run's rough time, which orders a first ``glu reproduce``.

``glu reproduce`` passes the quick preset and checks, after each notebook, that it wrote exactly what its
manifest declares (:func:`check_outputs`); the tests and ``glu readme`` read the same manifests.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from glu.errors import GluError

KINDS: tuple[str, ...] = ("figures", "tables", "recordings", "models")
"""The kinds of output a notebook declares, each a folder of the output layout (tables: ``results/``)."""
_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")
KEYS = frozenset({"about", "expected_seconds", "real_only", "quick", *KINDS})


class ManifestError(GluError):
    """A notebook's manifest is missing or malformed, or its outputs differ from it."""


@dataclass(frozen=True)
class Manifest:
    """A notebook's declaration of itself (see the module docstring)."""

    notebook: str
    about: str = ""
    expected_seconds: float | None = None
    figures: tuple[str, ...] = ()
    tables: tuple[str, ...] = ()
    recordings: tuple[str, ...] = ()
    models: tuple[str, ...] = ()
    real_only: frozenset[str] = frozenset()
    quick: Mapping[str, Any] = field(default_factory=dict)

    def outputs(self, kind: str, real: bool = True) -> tuple[str, ...]:
        """The names of ``kind`` it writes on the real data (``real``) or on synthetic data."""
        names = getattr(self, kind)
        return names if real else tuple(n for n in names if n not in self.real_only)


def header(path: str | os.PathLike) -> dict[str, Any]:
    """The ``jupyter:`` metadata of a jupytext percent file's header (``{}`` if it has none)."""
    import yaml

    lines = Path(path).read_text(encoding="utf-8").splitlines()
    if not lines or lines[0] != "# ---" or "# ---" not in lines[1:]:
        return {}
    end = lines.index("# ---", 1)
    try:
        meta = yaml.safe_load("\n".join(line[2:] for line in lines[1:end]))
    except yaml.YAMLError as e:
        raise ManifestError(f"{Path(path).name}: its header is not YAML ({e})") from None
    return (meta or {}).get("jupyter") or {}


def _names(value: Any, where: str) -> tuple[str, ...]:
    if value is None:
        return ()
    if not isinstance(value, list) or not all(isinstance(v, str) and _NAME.fullmatch(v) for v in value):
        raise ManifestError(f"{where}: must be a list of names (letters, digits, _ . -), got {value!r}")
    if len(set(value)) != len(value):
        raise ManifestError(f"{where}: a name is listed twice")
    return tuple(value)


def read_manifest(path: str | os.PathLike) -> Manifest:
    """The manifest in a notebook's header; :class:`ManifestError` naming the notebook if it is malformed."""
    path = Path(path)
    where = f"{path.stem}: the glu block of its header"
    block = header(path).get("glu")
    if not isinstance(block, dict):
        raise ManifestError(f"{where} is missing (see glu.run.manifest)")
    unknown = set(block) - KEYS
    if unknown:
        raise ManifestError(f"{where} has unknown keys {sorted(unknown)}; allowed: {sorted(KEYS)}")
    seconds = block.get("expected_seconds")
    if seconds is not None and (
        isinstance(seconds, bool) or not isinstance(seconds, int | float) or not 0 <= seconds < math.inf
    ):
        raise ManifestError(f"{where}: expected_seconds must be a number of seconds ≥ 0, got {seconds!r}")
    kinds = {k: _names(block.get(k), f"{where}, {k}") for k in KINDS}
    real_only = frozenset(_names(block.get("real_only"), f"{where}, real_only"))
    stray = real_only - {n for names in kinds.values() for n in names}
    if stray:
        raise ManifestError(f"{where}, real_only: {sorted(stray)} are not among its outputs")
    quick = block.get("quick") or {}
    if not isinstance(quick, dict):
        raise ManifestError(f"{where}, quick: must map parameter names to values, got {quick!r}")
    about = block.get("about") or ""
    if not isinstance(about, str):
        raise ManifestError(f"{where}, about: must be one line of text")
    return Manifest(
        path.stem,
        about,
        None if seconds is None else float(seconds),
        real_only=real_only,
        quick=dict(quick),
        **kinds,
    )


def written_outputs(root: Path) -> dict[str, set[str]]:
    """The names of what a notebook wrote under an output root, by kind (figures by stem, PNG or SVG)."""
    where = {  # kind → its folder, and the suffixes of its files (named by stem); models: any file, by name
        "figures": ("figures", (".png", ".svg")),
        "tables": ("results", (".csv",)),
        "recordings": ("recordings", (".rrd",)),
        "models": ("models", None),
    }
    out: dict[str, set[str]] = {}
    for kind, (folder, suffixes) in where.items():
        d = root / folder
        files = [f for f in d.iterdir() if f.is_file()] if d.is_dir() else []
        out[kind] = {f.stem for f in files if f.suffix in suffixes} if suffixes else {f.name for f in files}
    return out


def check_outputs(manifest: Manifest, written: Mapping[str, Iterable[str]], real: bool) -> None:
    """:class:`ManifestError` unless the notebook wrote exactly what its manifest declares for this data."""
    problems = []
    for kind in KINDS:
        declared, got = set(manifest.outputs(kind, real)), set(written.get(kind, ()))
        if got - declared:
            problems.append(f"{kind} not in its manifest: {', '.join(sorted(got - declared))}")
        if declared - got:
            problems.append(f"{kind} declared but not written: {', '.join(sorted(declared - got))}")
    if problems:
        raise ManifestError(
            f"{manifest.notebook} ({'real' if real else 'synthetic'} data): "
            + "; ".join(problems)
            + " (its manifest is the glu block of its header)"
        )
