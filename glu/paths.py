"""Where glu's inputs and outputs live, rooted at the package (never at the working directory).

The one owner of paths. glu runs in two settings, and :func:`locate` tells them apart:

* **a source checkout** (``git clone`` + ``pip install -e .``): the package sits beside ``pyproject.toml``
  and ``notebooks/``. Data fetched goes to ``data/real/``, notebook scratch runs to ``build/scratch/``, and
  ``glu reproduce`` publishes into the project's ``results/``, ``recordings/``, ``models/`` and
  ``build/figures/`` (the tracked ``figures/`` only from the real data); the machine code of the compiled
  HMM loops is cached in ``build/compiled/``, and the tables of heavy grids computed for a notebook in
  ``build/sweeps/``; the saved tables of the notebooks' full grids are committed in ``sweeps/``
  (:mod:`glu.saved`).
* **an installed package** (a wheel in any environment): nothing is ever written inside the package
  (``site-packages``). Data lives in the user's data folder (platformdirs: ``~/.local/share/glu/real`` on
  Linux, ``~/Library/Application Support/glu/real`` on macOS, ``%LOCALAPPDATA%\\glu\\real`` on Windows),
  scratch runs and compiled code in the user's cache folder, and ``glu reproduce`` needs ``-o DIR``. The
  notebooks ship inside the package as ``glu/notebooks/`` (the repository's ``notebooks/`` folder, copied
  into the wheel by ``setup.py``), so they run from any folder.

``--data DIR`` and ``$GLU_DATA_DIR`` win over both. Inputs: the package's resources, the notebooks, the
data folders (the *layout* inside a data folder belongs to :class:`glu.data.DataSource`). Outputs: an
:class:`OutputLayout` names the place of every kind of output, either the project's own (``results/``,
``recordings/``, ``models/`` at the top; the figures, the executed notebooks and the documentation site
under ``build/``) or one root holding them all (``glu reproduce -o DIR``, a notebook's ``out_dir``).
Notebooks (through :mod:`glu.run.outputs`) and ``glu reproduce`` both use it, so the two can never disagree.
``glu reproduce`` keeps its runs in the root's store (:data:`RUNS`, :mod:`glu.run.publish`) and makes each
place a symbolic link into the published run; the project's tracked ``figures/`` (:data:`FIGURES_DIR`) are
written only from a full run on the real data.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from glu.errors import OutputError

APP_NAME = "glu"
"""The application's name in the user's data and cache folders."""


@dataclass(frozen=True)
class Locations:
    """Where glu reads and writes, for one place the package is installed (see :func:`locate`).

    Attributes
    ----------
    package : the package's folder
    checkout : the source checkout holding it, or None for an installed package
    notebooks : the jupytext notebooks ``NN_name.py``
    data : the folder of fetched data (``real/`` under it)
    scratch : where notebooks run by hand write their outputs
    compiled : numba's cache of the compiled loops (:mod:`glu.jit`)
    sweeps : where the tables of heavy grids computed for a notebook are kept (:mod:`glu.saved`)
    saved : the saved tables of the notebooks' full grids (``sweeps/`` of a checkout; None installed)
    """

    package: Path
    checkout: Path | None
    notebooks: Path
    data: Path
    scratch: Path
    compiled: Path
    sweeps: Path | None = None
    saved: Path | None = None

    @property
    def real_data(self) -> Path:
        """Where ``glu data fetch`` puts the real data by default."""
        return self.data / "real"

    @property
    def real_data_label(self) -> str:
        """How messages name :attr:`real_data`: ``data/real/`` in a checkout, else the user's data folder."""
        return "data/real/" if self.checkout is not None else f"{self.real_data}{os.sep}"


def is_checkout(root: Path) -> bool:
    """True if ``root`` is glu's source tree: ``pyproject.toml``, ``notebooks/`` and ``glu/`` side by side."""
    return (root / "pyproject.toml").is_file() and (root / "notebooks").is_dir() and (root / "glu").is_dir()


def locate(package_dir: Path, user_data: Path | None = None, user_cache: Path | None = None) -> Locations:
    """The :class:`Locations` of a package installed at ``package_dir``.

    In a checkout everything is under the checkout; otherwise data goes to ``user_data`` and scratch runs
    to ``user_cache`` (default: platformdirs' user data and cache folders for ``glu``), never inside
    ``package_dir``.

    >>> import tempfile
    >>> site = Path(tempfile.mkdtemp()) / "site-packages"
    >>> loc = locate(site / "glu", user_data=Path("/home/me/.local/share/glu"),
    ...              user_cache=Path("/home/me/.cache/glu"))
    >>> loc.checkout is None, loc.notebooks == site / "glu" / "notebooks", loc.real_data.as_posix()
    (True, True, '/home/me/.local/share/glu/real')
    """
    package_dir = Path(package_dir)
    root = package_dir.parent
    if is_checkout(root):
        build = root / "build"
        return Locations(
            package_dir,
            root,
            root / "notebooks",
            root / "data",
            build / "scratch",
            build / "compiled",
            build / "sweeps",
            root / "sweeps",
        )
    if user_data is None or user_cache is None:
        import platformdirs

        user_data = user_data or Path(platformdirs.user_data_dir(APP_NAME, appauthor=False))
        user_cache = user_cache or Path(platformdirs.user_cache_dir(APP_NAME, appauthor=False))
    return Locations(
        package_dir,
        None,
        package_dir / "notebooks",
        user_data,
        user_cache / "scratch",
        user_cache / "compiled",
        user_cache / "sweeps",
    )


PACKAGE_DIR: Path = Path(__file__).resolve().parent
HERE: Locations = locate(PACKAGE_DIR)
"""Where this glu reads and writes.

:meta hide-value:
"""
PROJECT_ROOT: Path | None = HERE.checkout
"""The source checkout, or None when glu is installed from a wheel.

:meta hide-value:
"""
RESOURCES_DIR: Path = PACKAGE_DIR / "resources"
"""The package's resources (the grammar, schemas, the site's configuration, the published numbers).

:meta hide-value:
"""
NOTEBOOKS_DIR: Path = HERE.notebooks
"""The jupytext notebooks (``notebooks/`` in a checkout, ``glu/notebooks/`` in a wheel).

:meta hide-value:
"""

DATA_DIR: Path = HERE.data
"""The data folder (``data/`` in a checkout, else the user's data folder).

:meta hide-value:
"""
REAL_DATA_DIR: Path = HERE.real_data
"""Where ``glu data fetch`` puts the real data (``data/real/`` in a checkout, else the user's data folder).

:meta hide-value:
"""
DATA_ENV_VAR = "GLU_DATA_DIR"
"""Environment variable naming the data folder (or ``synthetic``)."""
SHARED_DATA_ENV_VAR = "GLU_SHARED_DATA"
"""Environment variable naming the shared copy of the real data that tests and CI read."""

FIGURES_DIR: Path | None = PROJECT_ROOT / "figures" if PROJECT_ROOT is not None else None
"""The project's tracked figures (the README shows them), written only from a full run on the real data.

:meta hide-value:
"""

PUBLISHED_KINDS: tuple[str, ...] = ("figures", "results", "recordings", "models")
"""Outputs a notebook writes and ``glu reproduce`` publishes."""
OUTPUT_KINDS: tuple[str, ...] = (*PUBLISHED_KINDS, "notebooks", "site")
"""Every kind of output: the published ones, the executed notebooks and the documentation site."""
RUNS = ".glu-runs"
"""Folder (under an output root) holding ``glu reproduce``'s runs: the one published, and the one being
staged (:mod:`glu.run.publish`).

:meta hide-value:
"""


@dataclass(frozen=True)
class OutputLayout:
    """The folder of each kind of output.

    Attributes
    ----------
    root : the folder that holds them (the project root, or ``--out``)
    figures, results, recordings, models : what notebooks write (PNG + SVG, CSV + JSON, ``.rrd``, JSON)
    notebooks : executed notebooks (``.ipynb``)
    site : the documentation site (:mod:`glu.run.site`)
    tracked_figures : the project's figures under version control (written only from a full run on the real
        data), or None outside the project
    """

    root: Path
    figures: Path
    results: Path
    recordings: Path
    models: Path
    notebooks: Path
    site: Path
    tracked_figures: Path | None = None

    @classmethod
    def project(cls) -> OutputLayout:
        """The project's own places: ``results/``, ``recordings/``, ``models/``, ``build/figures/``,
        ``build/notebooks/``, ``build/site/``; the tracked figures in ``figures/``."""
        r = PROJECT_ROOT
        if r is None:
            raise OutputError(
                f"glu is installed, not a source checkout: give an output folder (-o DIR); "
                f"nothing is written inside the package ({PACKAGE_DIR})"
            )
        return cls(
            r,
            r / "build" / "figures",
            r / "results",
            r / "recordings",
            r / "models",
            r / "build" / "notebooks",
            r / "build" / "site",
            tracked_figures=r / "figures",
        )

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
        """A new folder of its own for one run of a notebook that does not publish: :meth:`under`
        :func:`new_scratch_dir` (so no run overwrites an earlier one's outputs)."""
        return cls.under(new_scratch_dir(notebook))

    def folder(self, kind: str) -> Path:
        """The folder of one kind of output (one of :data:`OUTPUT_KINDS`)."""
        if kind not in OUTPUT_KINDS:
            raise OutputError(f"unknown output kind {kind!r}; allowed: {', '.join(OUTPUT_KINDS)}")
        return getattr(self, kind)

    def published(self) -> dict[str, Path]:
        """Kind → folder for the outputs a notebook writes (:data:`PUBLISHED_KINDS`)."""
        return {kind: self.folder(kind) for kind in PUBLISHED_KINDS}

    @property
    def store(self) -> Path:
        """Where ``glu reproduce`` keeps its runs (:data:`RUNS` under the root, :mod:`glu.run.publish`)."""
        return self.root / RUNS


SCRATCH_DIR: Path = HERE.scratch
"""Where notebooks run by hand (JupyterLab, nbconvert, papermill, ``glu run``) write their outputs:
``build/scratch/`` in a checkout, the user's cache folder otherwise.

:meta hide-value:
"""


def scratch_dir(notebook: str) -> Path:
    """The scratch folder of one notebook: ``build/scratch/<notebook>/`` in a checkout; each run by hand
    gets a folder of its own in it (:func:`new_scratch_dir`)."""
    return SCRATCH_DIR / notebook


def new_scratch_dir(notebook: str) -> Path:
    """A new, empty folder for one run of ``notebook`` by hand: ``build/scratch/<notebook>/<date>-<time>/``
    (``-2``, ``-3``, … when runs start in the same second), made here, so that two runs never share one."""
    import time

    stamp = time.strftime("%Y%m%d-%H%M%S")
    folder = scratch_dir(notebook)
    folder.mkdir(parents=True, exist_ok=True)
    for k in range(1, 10_000):
        run = folder / (stamp if k == 1 else f"{stamp}-{k}")
        try:
            run.mkdir()
            return run
        except FileExistsError:
            continue
    raise OutputError(f"{folder}: no new scratch folder could be made (10,000 runs this second)")


def notebook_file(name: str) -> Path:
    """The jupytext source of a notebook, ``notebooks/<name>.py``."""
    return NOTEBOOKS_DIR / f"{name}.py"


def shared_data_dir() -> Path | None:
    """The real data the reference tests use: ``$GLU_SHARED_DATA``, ``../shared/data`` (CI), or what
    ``glu data fetch`` downloaded (``data/real/`` in a checkout); None when none of them holds it, or when
    ``$GLU_SHARED_DATA`` is ``none`` (the suite as a fresh clone without the data runs it)."""
    env = os.environ.get(SHARED_DATA_ENV_VAR)
    if env == "none":
        return None
    candidates = [Path(env)] if env else []
    if PROJECT_ROOT is not None:
        candidates.append(PROJECT_ROOT.parent / "shared" / "data")
    candidates.append(REAL_DATA_DIR)
    for c in candidates:
        if (c / "affordance-words").is_dir():
            return c.resolve()
    return None
