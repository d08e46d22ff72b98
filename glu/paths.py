"""Where glu's inputs and outputs live, rooted at the project (never at the working directory).

The one owner of paths. Inputs: the package's resources, the notebooks, the data folders (the *layout*
inside a data folder belongs to :class:`glu.data.DataSource`). Outputs: an :class:`OutputLayout` names
the folder of every kind of output, either the project's own (``figures/``, ``results/``,
``recordings/``, ``models/`` at the top, executed notebooks and the report under ``build/``) or one root
holding them all (``glu reproduce --out DIR``, a notebook's ``out_dir``). Notebooks (through
:mod:`glu.outputs`) and ``glu reproduce`` both use it, so the two can never disagree.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

PACKAGE_DIR: Path = Path(__file__).resolve().parent
PROJECT_ROOT: Path = PACKAGE_DIR.parent
RESOURCES_DIR: Path = PACKAGE_DIR / "resources"
NOTEBOOKS_DIR: Path = PROJECT_ROOT / "notebooks"

DATA_DIR: Path = PROJECT_ROOT / "data"
REAL_DATA_DIR: Path = DATA_DIR / "real"
DATA_ENV_VAR = "GLU_DATA_DIR"
"""Environment variable naming the data folder (or ``synthetic``)."""
SHARED_DATA_ENV_VAR = "GLU_SHARED_DATA"
"""Environment variable naming the shared copy of the real data that tests and CI read."""

PUBLISHED_KINDS: tuple[str, ...] = ("figures", "results", "recordings", "models")
"""Outputs a notebook writes and ``glu reproduce`` publishes."""
OUTPUT_KINDS: tuple[str, ...] = (*PUBLISHED_KINDS, "notebooks", "report")
"""Every kind of output: the published ones, the executed notebooks and the browsable report."""
STAGING = ".glu-staging"
"""Folder (under an output root) where a ``glu reproduce`` run stages its files until they are published."""


@dataclass(frozen=True)
class OutputLayout:
    """The folder of each kind of output.

    Attributes
    ----------
    root : the folder that holds them (the project root, or ``--out``)
    figures, results, recordings, models : what notebooks write (PNG + SVG, CSV + JSON, ``.rrd``, JSON)
    notebooks : executed notebooks (``.ipynb``)
    report : the browsable HTML report
    """

    root: Path
    figures: Path
    results: Path
    recordings: Path
    models: Path
    notebooks: Path
    report: Path

    @classmethod
    def project(cls) -> OutputLayout:
        """The project's own folders: ``figures/``, ``results/``, ``recordings/``, ``models/``, ``build/…``."""
        r = PROJECT_ROOT
        return cls(r, r / "figures", r / "results", r / "recordings", r / "models",
                   r / "build" / "notebooks", r / "build" / "report")  # fmt: skip

    @classmethod
    def under(cls, root: str | os.PathLike) -> OutputLayout:
        """Every kind in a folder of its name under ``root`` (``root/figures``, …, ``root/notebooks``)."""
        r = Path(root)
        return cls(r, *(r / kind for kind in OUTPUT_KINDS))

    @classmethod
    def at(cls, root: str | os.PathLike | None) -> OutputLayout:
        """:meth:`under` ``root``, or :meth:`project` for None."""
        return cls.project() if root is None else cls.under(Path(root).resolve())

    @classmethod
    def scratch(cls, notebook: str) -> OutputLayout:
        """A notebook's own scratch folder, for runs that do not publish: :meth:`under` ``scratch_dir(notebook)``."""
        return cls.under(scratch_dir(notebook))

    def folder(self, kind: str) -> Path:
        """The folder of one kind of output (one of :data:`OUTPUT_KINDS`)."""
        if kind not in OUTPUT_KINDS:
            raise ValueError(f"unknown output kind {kind!r}; allowed: {', '.join(OUTPUT_KINDS)}")
        return getattr(self, kind)

    def published(self) -> dict[str, Path]:
        """Kind → folder for the outputs a notebook writes (:data:`PUBLISHED_KINDS`)."""
        return {kind: self.folder(kind) for kind in PUBLISHED_KINDS}

    @property
    def staging(self) -> Path:
        """Where ``glu reproduce`` stages runs before publishing them."""
        return self.root / STAGING


SCRATCH_DIR: Path = PROJECT_ROOT / "build" / "scratch"
"""Where notebooks run by hand (JupyterLab, nbconvert, papermill, ``glu run``) write their outputs."""


def scratch_dir(notebook: str) -> Path:
    """The scratch folder of one notebook: ``build/scratch/<notebook>/``."""
    return SCRATCH_DIR / notebook


def notebook_file(name: str) -> Path:
    """The jupytext source of a notebook, ``notebooks/<name>.py``."""
    return NOTEBOOKS_DIR / f"{name}.py"


def shared_data_dir() -> Path | None:
    """The shared copy of the real data used by tests and CI (``$GLU_SHARED_DATA`` or ``../shared/data``)."""
    env = os.environ.get(SHARED_DATA_ENV_VAR)
    candidates = [Path(env)] if env else []
    candidates.append(PROJECT_ROOT.parent / "shared" / "data")
    for c in candidates:
        if (c / "affordance-words").is_dir():
            return c.resolve()
    return None
