"""What every experiment shares: the tidy frame it returns, stamped with where its numbers come from.

Each experiment function returns a tidy :class:`pandas.DataFrame` (one row per number behind a figure)
whose ``attrs`` say what it is, set here and nowhere else:

``experiment``
    the experiment's name (also the default name of its result table);
``data_source``
    which data the numbers come from (:meth:`glu.data.DataSource.describe`, a model's provenance, or a
    corpus's description);
``parameters``
    the settings that produced it (seeds, folds, rules, …), so a table can be rerun.

:class:`glu.run.outputs.Outputs` writes all three into the table's JSON file and ``results/summary.json``.

:func:`html_table` is how a notebook shows such a frame (:func:`glu.run.notebook.start` makes it the
kernel's HTML form of every DataFrame): numbers rounded for reading, missing values as a dash, no
``0 … n-1`` index, an estimate's interval under it, and headers that may wrap, so that a table fits the
page. The files keep every digit.
"""

from __future__ import annotations

import html
import math
import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from glu.hmm import TrainingConfig

UNKNOWN_SOURCE = "unknown data"


def tidy(df: pd.DataFrame, experiment: str, data_source: str, **parameters: Any) -> pd.DataFrame:
    """Stamp ``df`` with its experiment, data source and parameters (``df.attrs``); returns ``df``."""
    df.attrs["experiment"] = experiment
    df.attrs["data_source"] = str(data_source)
    df.attrs["parameters"] = {k: _plain(v) for k, v in parameters.items()}
    return df


def model_source(model: Any) -> str:
    """The data source recorded in a model's ``meta`` (a :class:`~glu.bn.BayesNet` or a recogniser)."""
    meta = getattr(model, "meta", None) or {}
    return str(meta.get("data_source") or meta.get("data") or UNKNOWN_SOURCE)


def corpus_source(sequences: Sequence[Any]) -> str:
    """The description of a gesture corpus (:class:`glu.gestures.corpus.Corpus`), if it has one."""
    return str(getattr(sequences, "description", "") or UNKNOWN_SOURCE)


def training_parameters(config: TrainingConfig | None, features: Any = None) -> dict[str, Any]:
    """The training settings to stamp on a table: the fields of ``config`` that differ from glu's defaults,
    and the invariant features when given (``{}`` for the defaults on raw features)."""
    config = config or TrainingConfig()
    default = TrainingConfig()
    out = {k: v for k, v in config.as_dict().items() if v != getattr(default, k)}
    if features is not None:
        out["features"] = features
    return out


def _plain(v: Any) -> Any:
    """A parameter value as JSON-ready data (tuples → lists, mappings → dicts, settings objects → their
    name)."""
    if hasattr(v, "name") and hasattr(v, "to_dict"):  # e.g. gesture Invariants: "centred+rotated"
        return v.name
    if isinstance(v, Mapping):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_plain(x) for x in v]
    if hasattr(v, "item") and callable(v.item):
        return v.item()
    return v


# ------------------------------------------------------------------------------------------ display
MISSING = "—"
"""How :func:`html_table` shows a missing value (NaN, None)."""

_INTERVAL = re.compile(r"^(\S+) (\[[^\]]+\])$")
"""A cell ``"0.76 [0.67, 0.84]"``: an estimate and its interval."""


def _missing(x: Any) -> bool:
    return x is None or (isinstance(x, float) and math.isnan(x)) or x is pd.NA or x is pd.NaT


def decimals(values: np.ndarray) -> int | None:
    """How many decimals a column of floats is shown with: none when every value is whole, 3 up to 1 (a
    probability, an accuracy), 2 below 100, 1 above; None (three significant digits, each value on its own)
    when all are below 0.01. ``values``: array of floats, shape (n,) (NaN and ±inf ignored)."""
    finite = values[np.isfinite(values)]
    if finite.size == 0 or np.all(finite == np.round(finite)):
        return 0
    top = float(np.max(np.abs(finite)))
    return None if top < 0.01 else 3 if top <= 1 else 2 if top < 100 else 1


def _float_cell(digits: int | None) -> Callable[[Any], str]:
    def show(x: Any) -> str:
        if _missing(x):
            return MISSING
        return f"{x:.3g}" if digits is None else f"{x:.{digits}f}"

    return show


def _breakable(text: str) -> str:
    """Escaped text that may wrap after ``+``, ``_`` and ``/`` (``norobotview_tap_notable_seated_2``)."""
    return re.sub(r"([+_/])", r"\1<wbr>", html.escape(text))


def _text_cell(x: Any) -> str:
    text = str(x)
    m = _INTERVAL.match(text)
    if m:  # the estimate, and its interval under it
        return f'{html.escape(m.group(1))}<br><span class="glu-interval">{html.escape(m.group(2))}</span>'
    return _breakable(text)


def _with_intervals(df: pd.DataFrame) -> pd.DataFrame:
    """Each estimate column followed by its ``ci_low…`` and ``ci_high…`` columns (the same suffix: ``ci_low``,
    ``ci_low_grasp``) made one column of ``"estimate [low, high]"`` cells."""
    if isinstance(df.columns, pd.MultiIndex):
        return df
    cols = [str(c) for c in df.columns]
    out = df.copy()
    for i, col in enumerate(cols[:-2]):
        low, high = cols[i + 1], cols[i + 2]
        if not (low.startswith("ci_low") and high == "ci_high" + low[len("ci_low") :]):
            continue
        if not all(pd.api.types.is_float_dtype(df[c]) for c in (col, low, high)):
            continue
        show = _float_cell(decimals(df[[col, low, high]].to_numpy(dtype=float).ravel()))
        out[col] = [
            show(e) if _missing(lo) or _missing(hi) else f"{show(e)} [{show(lo)}, {show(hi)}]"
            for e, lo, hi in zip(df[col], df[low], df[high], strict=True)
        ]
        out = out.drop(columns=[low, high])
    return out


def _header(label: Any) -> str:
    """A header that may wrap after ``+``, ``_`` and ``/`` (``centred+rotated``, ``label_accuracy``)."""
    return _breakable(str(label))


def html_table(df: pd.DataFrame, max_rows: int = 60) -> str:
    """``df`` as an HTML table for reading: each float column at the decimals of :func:`decimals`, missing
    values as :data:`MISSING`, intervals under their estimates (an estimate's ``ci_low``/``ci_high`` columns
    joined to it), text and headers that may wrap; the index left out when it is the default ``0 … n-1``.
    At most ``max_rows`` rows (the first and last halves)."""
    shown = _with_intervals(df)
    formatters: dict[Any, Callable[[Any], str]] = {}
    for col in shown.columns:
        values = shown[col]
        if pd.api.types.is_float_dtype(values):
            formatters[col] = _float_cell(decimals(values.to_numpy(dtype=float)))
        elif pd.api.types.is_bool_dtype(values) or pd.api.types.is_integer_dtype(values):
            formatters[col] = lambda x: MISSING if _missing(x) else str(x)
        else:
            formatters[col] = _text_cell
        if values.hasnans and (
            values.dtype == object or isinstance(values.dtype, pd.api.extensions.ExtensionDtype)
        ):
            shown[col] = values.astype(object).where(values.notna(), np.nan)  # to_html writes pd.NA as "<NA>"
    default_index = (
        isinstance(shown.index, pd.RangeIndex) and shown.index.start == 0 and shown.index.step == 1
    )
    shown = shown.rename(columns=_header, index=lambda v: html.escape(str(v)))
    formatters = {
        _header(k) if not isinstance(k, tuple) else tuple(map(_header, k)): f for k, f in formatters.items()
    }
    shown.columns.names = [_header(n) if n is not None else None for n in shown.columns.names]
    shown.index.names = [html.escape(str(n)) if n is not None else None for n in shown.index.names]
    return shown.to_html(
        formatters=formatters,
        index=not default_index,
        escape=False,
        border=0,
        classes="glu-table",
        max_rows=max_rows,
        na_rep=MISSING,
    )
