"""Where the code runs: in a notebook kernel that a person watches, or headless.

Interactive extras (the evidence explorer's widgets, the Rerun viewer in a notebook) appear only in a
live kernel; headless runs (``glu reproduce``, ``glu run``: their kernels have ``GLU_HEADLESS=1``) and
plain Python show the static form. The tests force either with :func:`is_live`'s ``force`` argument.
"""

from __future__ import annotations

import os

HEADLESS_ENV = "GLU_HEADLESS"
"""Environment variable set (to ``1``) in the kernels of headless runs."""


def in_kernel() -> bool:
    """True when running inside an IPython kernel (a notebook), where outputs can be displayed."""
    try:
        from IPython import get_ipython
    except ImportError:  # pragma: no cover - IPython comes with ipykernel
        return False
    shell = get_ipython()
    return shell is not None and getattr(shell, "kernel", None) is not None


def is_live(force: bool | None = None) -> bool:
    """True in a kernel that is not headless (a person may interact); ``force`` overrides the guess."""
    if force is not None:
        return force
    return in_kernel() and os.environ.get(HEADLESS_ENV, "") in ("", "0")
