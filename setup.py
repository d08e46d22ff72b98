"""The one packaging setting pyproject.toml cannot express: ``notebooks/`` ships as the package ``glu.notebooks``.

Everything else is in ``pyproject.toml``. The notebooks stay at the top of the repository, where readers and
JupyterLab find them; mapped into the package, a wheel carries them, so an installed glu runs them from any
folder (``glu reproduce -o DIR``). The packages are found (``glu`` and every subpackage) rather than listed,
so a new subpackage cannot be left out of the wheel.
"""

from setuptools import find_packages, setup

setup(
    packages=[*find_packages(include=["glu", "glu.*"]), "glu.resources", "glu.notebooks"],
    package_dir={"glu.notebooks": "notebooks"},
)
