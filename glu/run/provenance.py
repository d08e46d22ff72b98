"""Which glu made a run: its version and the git commit of the checkout, "modified" when the code differs.

Every record of a run names it: ``results/summary.json`` (``made_by``, ``provenance``), the site's index,
``figures/rendered-with.json`` and the footer of every figure (:meth:`glu.run.outputs.Outputs.figure`).
``glu reproduce`` reads it once and hands it to the notebooks' kernels (:data:`ENV`), so that every output
of one run names the same state even if the tree changes while it runs.

The tree is *modified* when ``git status`` shows a change outside the run's own outputs (:data:`OUTPUTS`:
the figures, results, recordings and models a run rewrites): code, notebooks, docs, an untracked file. A
figure's footer thus changes with the commit, and a figure is byte-identical only for the same commit and
data. Published figures are made from a clean tree, so that the commit in their footer reproduces them
(``CHANGELOG.md``, "How the figures are published"). An installed glu (no checkout) names its version only.
"""

from __future__ import annotations

import os
import subprocess
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import glu
from glu import paths

ENV = "GLU_MADE_BY"
"""Environment variable through which ``glu reproduce`` gives its notebooks the line naming the run's glu."""

OUTPUTS = ("figures", "results", "recordings", "models")
"""The folders a run rewrites: a change there does not make the tree "modified"."""

SHORT = 12
"""Digits of the commit shown in footers and pages (the summary keeps all 40)."""


@dataclass(frozen=True)
class Provenance:
    """The glu that made a run: ``version`` (``glu.__version__``), ``commit`` (the checkout's HEAD, or None
    outside a git checkout) and ``modified`` (the code differs from that commit)."""

    version: str
    commit: str | None = None
    modified: bool = False

    def label(self) -> str:
        """``glu 0.1.0, commit 1a2b3c4d5e6f`` (``(modified)`` after it when the tree differs)."""
        if self.commit is None:
            return f"glu {self.version}"
        return f"glu {self.version}, commit {self.commit[:SHORT]}" + (" (modified)" if self.modified else "")

    def as_dict(self) -> dict[str, object]:
        """For ``results/summary.json``."""
        return {"version": self.version, "commit": self.commit, "modified": self.modified}


def _git(root: Path, *args: str) -> str | None:
    try:
        done = subprocess.run(
            ["git", "-C", str(root), *args], capture_output=True, text=True, timeout=30, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout if done.returncode == 0 else None


def read_provenance(root: Path | None = paths.PROJECT_ROOT) -> Provenance:
    """The provenance of the checkout at ``root`` (git's view of it now; no checkout: the version only)."""
    if root is None:
        return Provenance(glu.__version__)
    head = _git(root, "rev-parse", "--verify", "HEAD")
    if head is None:
        return Provenance(glu.__version__)
    status = _git(root, "status", "--porcelain", "--", ".", *(f":(exclude){d}" for d in OUTPUTS))
    return Provenance(glu.__version__, head.strip(), modified=status is None or bool(status.strip()))


_this_checkout = cache(read_provenance)  # this checkout's provenance, read once per process


def made_by() -> str:
    """The line naming the glu of this run: the one ``glu reproduce`` passed (:data:`ENV`), else this
    checkout's (read once per process)."""
    return os.environ.get(ENV) or _this_checkout().label()
