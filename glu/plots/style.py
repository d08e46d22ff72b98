"""The look shared by every figure: colours, figure sizes, deterministic saving, the data-source footer.

Figures are saved with :func:`save_figure`, which writes PNG (at :data:`DPI`) and SVG that are
byte-identical across runs (no software/date metadata, fixed SVG hash salt, written atomically), and
every figure carries a footer naming its data source (:func:`stamp`). The backend is left alone: the
inline backend in a notebook, a non-interactive one on a headless machine; saving works with any.
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Sequence
from contextlib import nullcontext
from pathlib import Path
from typing import Any

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from glu.files import atomic_path, atomic_write_text
from glu.plots.overlap import CHECK_ENV, watching

matplotlib.rcParams["svg.hashsalt"] = "glu"
DPI = 150
"""Resolution of the saved PNGs (dots per inch)."""

ACTION_COLORS = {"grasp": "#4C72B0", "tap": "#DD8452", "touch": "#55A868", "push": "#8172B3"}
VALUE_COLORS = {"slow": "#8DA0CB", "medium": "#FC8D62", "fast": "#66C2A5"}
ORIGINAL_MARK = {"marker": "_", "color": "black", "markersize": 14, "markeredgewidth": 2, "linestyle": "none"}
"""How the original model's values are marked on a figure of ours: a short black bar."""
ORIGINAL_LABEL = "original model (BN_lab.mat)"
"""Legend entry of the original model's values, drawn with :data:`ORIGINAL_MARK`."""
WORD_COLORS = {"and": "#4C72B0", "but": "#DD8452"}
"""The two conjunctions of TCDS Fig. 7 (and sentences containing them)."""
RULE_LABELS = {
    "virtual": "virtual evidence",
    "jeffrey": "Jeffrey's rule",
    "hard": "hard decision",
    "product": "product rule",
}
"""How figures name the fusion rules (``jeffrey`` is Jeffrey's rule, a proper name)."""
STRATEGY_LABELS = {
    "gesture": "gesture (HMMs alone)",
    "network": "network alone",
    **RULE_LABELS,
    "true_action": "true action given",
}
"""How figures name the fusion strategies: the rules of :data:`glu.fusion.STRATEGIES` and the baselines
they are compared with (the gesture recogniser alone, the network alone, the true action given)."""
STRATEGY_COLORS = {
    "gesture": "#8C8C8C",
    "network": "#937860",
    "hard": "#C44E52",
    "virtual": "#4C72B0",
    "jeffrey": "#55A868",
    "product": "#DD8452",
    "true_action": "#222222",
}
"""A colour per strategy of :data:`STRATEGY_LABELS`."""
STRATEGY_MARKERS = {
    "gesture": "s",
    "network": "D",
    "hard": "v",
    "virtual": "^",
    "jeffrey": "o",
    "product": "P",
    "true_action": "X",
}
"""A marker per strategy of :data:`STRATEGY_LABELS`, so that no strategy is told from another by its colour
alone (colour-blind readers, greyscale prints)."""
STRATEGY_LINESTYLES = {"gesture": "--", "network": "--", "true_action": ":"}
"""Line styles of the strategies drawn as lines with markers: the baselines dashed, the true action (an
oracle) dotted, the rules solid (:func:`strategy_style`)."""
RULE_LINESTYLES = {"virtual": "-", "jeffrey": "--", "hard": ":", "product": "-"}
"""Line styles of the rules where a line has no marker and its colour means something else (the sweeps of
p_HMM, coloured by value): the rules a sweep draws together (virtual evidence and Jeffrey's rule) differ by
line style alone; the product rule is swept on its own."""
FOOTER_SIZE = 7.5
"""Points: the footer naming the data."""


def rule_label(rule: str) -> str:
    """The fusion rule ``rule`` as figures name it (:data:`RULE_LABELS`), else ``rule`` itself."""
    return RULE_LABELS.get(rule, rule)


def strategy_label(strategy: str) -> str:
    """A fusion strategy as figures name it (:data:`STRATEGY_LABELS`), else ``strategy`` itself."""
    return STRATEGY_LABELS.get(strategy, strategy)


def strategy_style(strategy: str) -> dict[str, str]:
    """How a strategy's line is drawn (keywords of ``Axes.plot`` and ``Axes.errorbar``): its colour
    (:data:`STRATEGY_COLORS`), line style (:data:`STRATEGY_LINESTYLES`, else solid) and marker
    (:data:`STRATEGY_MARKERS`); black circles for a strategy not named there."""
    return {
        "color": STRATEGY_COLORS.get(strategy, "black"),
        "ls": STRATEGY_LINESTYLES.get(strategy, "-"),
        "marker": STRATEGY_MARKERS.get(strategy, "o"),
    }


def legend_right(ax: Axes, fontsize: float | str = 8, **kwargs: Any) -> Any:
    """A frameless legend right of ``ax``, its top level with the axes' top (where the figures keep their
    legends); ``kwargs`` go to :meth:`~matplotlib.axes.Axes.legend` (handles, title, …)."""
    return ax.legend(fontsize=fontsize, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0), **kwargs)


def balanced_fill(text: str, width: int) -> str:
    """``text`` in lines of at most ``width`` characters (not broken at hyphens), as few as
    :func:`textwrap.fill` makes, and as even in length as the words allow (no lone word on a last line)."""
    lines = textwrap.wrap(text, width, break_on_hyphens=False)
    for w in range(-(-len(text) // len(lines)) if len(lines) > 1 else width, width):
        even = textwrap.wrap(text, w, break_on_hyphens=False)
        if len(even) <= len(lines):
            return "\n".join(even)
    return "\n".join(lines)


def save_figure(fig: Figure, path: str | os.PathLike, formats: Sequence[str] = ("png", "svg")) -> list[Path]:
    """Save ``fig`` as ``path.<fmt>`` for each format, deterministically; returns the files written.

    With the environment variable ``GLU_FIGURE_CHECK`` naming a folder by an absolute path (each notebook's
    kernel runs in a folder of its own), the readability problems of the PNG as it is drawn
    (:func:`glu.plots.overlap.watching`, one per line) are written there, to ``<name>.txt``; the files are
    the same with and without the check.
    """
    path = Path(path)
    check = os.environ.get(CHECK_ENV)
    if check and not Path(check).is_absolute():  # taken in each kernel's own folder, it would scatter
        raise ValueError(
            f"{CHECK_ENV} names the folder for the readability checks by an absolute path, not {check!r}"
        )
    path.parent.mkdir(parents=True, exist_ok=True)
    out = []
    for fmt in formats:
        target = path.with_suffix(f".{fmt}")
        meta = {"png": {"Software": None}, "svg": {"Date": None}, "pdf": {"CreationDate": None}}.get(fmt, {})
        watch = check and fmt == "png"  # the test suite's readability check (glu.plots.overlap)
        with watching(fig) if watch else nullcontext([]) as problems, atomic_path(target) as tmp:
            fig.savefig(tmp, format=fmt, metadata=meta, bbox_inches="tight", dpi=DPI)
        if watch:
            atomic_write_text(Path(check) / f"{path.name}.txt", "".join(f"{p}\n" for p in problems))
        out.append(target)
    return out


def stamp(fig: Figure, footer: str, made_by: str = "") -> None:
    """Lay the figure out, then write ``footer`` (its data source, …) in small grey text below everything,
    and ``made_by`` (the glu that drew it: version and commit) on a line of its own under it.

    A figure made with a layout engine (``layout="constrained"``, for legends outside every panel) keeps
    it; any other is laid out once with ``tight_layout``. The footer is written below the figure's
    bottom edge, so it cannot overlap anything the layout placed, in lines about as wide as the figure.
    """
    if fig.get_layout_engine() is None:
        fig.tight_layout()
    chars = int(fig.get_figwidth() * 72 / (0.56 * FOOTER_SIZE))  # about as wide as the figure
    lines = textwrap.wrap(footer, max(chars, 40), break_on_hyphens=False)
    text = fig.text(0.005, -0.01, "\n".join(lines), fontsize=FOOTER_SIZE, color="0.3", ha="left", va="top")
    if made_by:  # on a line of its own under the footer as matplotlib lays it out (measured, not assumed)
        box = text.get_window_extent(fig.canvas.get_renderer())
        gap = 0.2 * FOOTER_SIZE / 72 * fig.dpi  # a fifth of a line, in pixels
        below = (box.y0 - gap) / fig.bbox.height
        fig.text(0.005, below, made_by, fontsize=FOOTER_SIZE, color="0.45", ha="left", va="top")


def new_figure(
    ncols: int = 1, width: float = 4.2, height: float = 3.2, nrows: int = 1, **kwargs
) -> tuple[Figure, list[Axes]]:
    """A figure with ``nrows`` × ``ncols`` axes of ``width`` × ``height`` inches each, listed row by row.

    ``kwargs`` go to :func:`matplotlib.pyplot.subplots` (``sharex``, ``sharey``, ``layout``, …).
    """
    fig, axes = plt.subplots(nrows, ncols, figsize=(width * ncols, height * nrows), squeeze=False, **kwargs)
    return fig, list(axes.flat)


def bars_with_original(ax: Axes, x: np.ndarray, p: np.ndarray, colors, original: np.ndarray | None) -> None:
    """Bars of ``p`` at ``x``, and the original model's values as black marks (if given).

    ``x`` (bar positions), ``p`` (probabilities) and ``original``: shape (n_bars,); ``colors``: one per bar.
    """
    ax.bar(x, p, color=colors, edgecolor="0.2", linewidth=0.6)
    if original is not None:
        ax.plot(x, original, **ORIGINAL_MARK, label=ORIGINAL_LABEL)
