"""The one packaging step pyproject.toml cannot express: ``notebooks/`` ships inside the wheel as ``glu/notebooks/``.

Everything else is in ``pyproject.toml``. The notebooks stay at the top of the repository, where readers and
JupyterLab find them; copied into the package when a wheel is built, they run from any folder once glu is
installed (``glu reproduce -o DIR``). An editable install (``make venv``) needs no copy: glu finds them in
the checkout (:mod:`glu.paths`).

The packages are found (``glu`` and every subpackage) rather than listed, so a new subpackage cannot be left
out of the wheel; the folders of resources (``glu/resources/…``, no ``__init__.py``) are found as the
namespace packages Python sees in them, so setuptools ships them as the data they are without a word. The
layout is the simplest setuptools knows (``package_dir`` = the checkout), so an editable install is a plain
path entry and prints nothing either.
"""

import shutil
from pathlib import Path

from setuptools import find_namespace_packages, setup
from setuptools.command.build_py import build_py


class BuildWithNotebooks(build_py):
    """``build_py``, then the notebooks (``notebooks/*.py``) copied into ``glu/notebooks/``."""

    def run(self) -> None:
        super().run()
        if self.editable_mode:
            return
        target = Path(self.build_lib, "glu", "notebooks")
        target.mkdir(parents=True, exist_ok=True)
        for notebook in sorted(Path("notebooks").glob("*.py")):
            shutil.copy2(notebook, target / notebook.name)


setup(
    packages=find_namespace_packages(include=["glu", "glu.*"], exclude=["*.__pycache__"]),
    package_dir={"": "."},
    cmdclass={"build_py": BuildWithNotebooks},
)
