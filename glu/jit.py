"""Compiled loops (numba), as glu compiles them: machine code cached on disk, numba imported on first use.

:func:`compiled` turns a module-level function of plain loops into machine code once per process. The code
is cached (``build/compiled/`` in a checkout, the user's cache folder for an installed package:
:attr:`glu.paths.Locations.compiled`; ``$NUMBA_CACHE_DIR`` wins), so only the first process on a machine
compiles it and later ones load it. numba itself is imported when the first such function is called, so
code that never needs one never pays for the import. The compiled loops: the HMM recursions
(:mod:`glu.hmm._engine`) and the network's planning (:mod:`glu.bn.kernels`).
"""

from __future__ import annotations

import types
from functools import cache
from typing import Any


@cache
def _jit() -> Any:
    """numba's ``njit`` as glu compiles with it: machine code cached on disk
    (:attr:`glu.paths.Locations.compiled`, never inside an installed package; ``$NUMBA_CACHE_DIR`` wins), no
    GIL, numpy's error model (a division by zero gives inf or nan, as the array code did)."""
    import numba

    from glu.paths import HERE

    if not numba.config.CACHE_DIR:
        numba.config.CACHE_DIR = str(HERE.compiled)
    return numba.njit(cache=True, nogil=True, error_model="numpy")


@cache
def compiled(fn: Any) -> Any:
    """``fn`` (a module-level function of plain loops) compiled by numba, once per process; its machine
    code comes from the cache after the first process.

    The functions of ``fn``'s own module that it calls by name (helpers of plain loops, such as the E- and
    M-steps of :func:`glu.hmm._engine.gmm.gmm_em`'s loop) are compiled first and their module names bound
    to the compiled ones, so that compiled code calls compiled code (a helper asked for after that is
    already compiled, and comes back as it is)."""
    if not isinstance(fn, types.FunctionType):
        return fn
    for name in fn.__code__.co_names:
        helper = fn.__globals__.get(name)
        if isinstance(helper, types.FunctionType) and helper.__module__ == fn.__module__ and helper is not fn:
            fn.__globals__[name] = compiled(helper)
    return _jit()(fn)
