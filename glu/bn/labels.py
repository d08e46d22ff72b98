"""Labelled results at array speed: each node's value index made once, Series made without copies.

The engines' labelled results (:meth:`~glu.bn.inference.Engine.posterior`, ``marginals``, ``posteriors``,
``word_probabilities``, ``posterior_table``) are ordinary pandas objects. Making a pandas ``Index`` of the
value names costs tens of microseconds — more than an answer — so :class:`Labels` makes each node's once,
and :func:`series` wraps an answer in a Series around that index without copying either (through pandas'
own block constructor when this pandas has it and it gives the same Series as ``pd.Series``; else through
``pd.Series`` itself).

>>> import numpy as np
>>> s = series(np.array([0.25, 0.75]), Labels({"Rain": ("no", "yes")}.get).index("Rain"), "Rain")
>>> s.to_dict(), s.name, s.index.name
({'no': 0.25, 'yes': 0.75}, 'Rain', 'Rain')
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd


def _public(values: np.ndarray, index: pd.Index, name: str) -> pd.Series:
    return pd.Series(values, index=index, name=name, copy=False)


def _from_blocks() -> Callable[[np.ndarray, pd.Index, str], pd.Series] | None:
    """pandas' block constructor as a Series maker, if it exists here and agrees with ``pd.Series``."""
    try:
        from pandas.core.internals import SingleBlockManager

        def make(values: np.ndarray, index: pd.Index, name: str) -> pd.Series:
            """A Series of ``values`` (shape (k,)) over ``index`` (k labels), named ``name``, one block."""
            mgr = SingleBlockManager.from_array(values, index)
            s = pd.Series._from_mgr(mgr, axes=mgr.axes)
            object.__setattr__(s, "_name", name)  # what ``s.name = name`` stores, without its checks
            return s

        probe = np.array([0.25, 0.75])
        idx = pd.Index(["a", "b"], name="x")
        pd.testing.assert_series_equal(make(probe, idx, "x"), _public(probe, idx, "x"))
        return make
    except Exception:  # noqa: BLE001 - any other pandas: the public constructor
        return None


_make = _from_blocks() or _public


def series(values: np.ndarray, index: pd.Index, name: str) -> pd.Series:
    """A float Series of ``values`` (shape (k,)) over ``index``, named ``name`` (no copy of either)."""
    return _make(values, index, name)


class Labels:
    """Each node's values (``values(node)``) as a pandas ``Index`` named after the node, made on first use."""

    def __init__(self, values: Callable[[str], Sequence[str]]) -> None:
        self._values = values
        self._index: dict[str, pd.Index] = {}

    def index(self, node: str) -> pd.Index:
        """``node``'s values as an Index named ``node``."""
        idx = self._index.get(node)
        return idx if idx is not None else self.named(node, self._values(node), node)

    def named(self, key: str, names: Sequence[str], name: str) -> pd.Index:
        """Any other fixed index (e.g. the word names), made once under ``key``."""
        idx = self._index.get(key)
        if idx is None:
            idx = self._index[key] = pd.Index(list(names), name=name)
        return idx
