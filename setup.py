"""The one packaging setting pyproject.toml cannot express: ``notebooks/`` ships as the package ``glu.notebooks``.

Everything else is in ``pyproject.toml``. The notebooks stay at the top of the repository, where readers and
JupyterLab find them; mapped into the package, a wheel carries them, so an installed glu runs them from any
folder (``glu reproduce -o DIR``). The packages are found (``glu`` and every subpackage) rather than listed,
so a new subpackage cannot be left out of the wheel; the folders of ``glu/resources/`` (data, no Python) are
found as namespace packages, so that setuptools knows they belong to the package.

An editable install (``pip install -e .``, ``make venv``) maps nothing: a checkout finds its notebooks in
``notebooks/`` itself (:func:`glu.paths.locate`), and a plain layout lets setuptools install it with a path
entry and no warning (a mapped folder makes it warn on every install).
"""

import sys

from setuptools import find_namespace_packages, find_packages, setup

PACKAGES = [*find_packages(include=["glu", "glu.*"]), *find_namespace_packages(include=["glu.resources*"])]
EDITABLE = "editable_wheel" in sys.argv

setup(
    packages=sorted(set(PACKAGES)) if EDITABLE else sorted({*PACKAGES, "glu.notebooks"}),
    package_dir={"": "."} if EDITABLE else {"glu.notebooks": "notebooks"},
)
