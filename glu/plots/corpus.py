"""The figures of the corpus evaluation, whole: panels of :mod:`glu.plots.evaluation` and one legend each.

Each function takes the sweep's tables (:mod:`glu.sweep`) and returns a laid-out figure (constrained
layout; the legend above the panels, naming every strategy drawn once). The panels are one column per cell
of the design given (``cells``: e.g. the reference cell and the most mismatched one,
:func:`glu.experiments.findings.contrast_cells`), to fit a page.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import matplotlib.pyplot as plt
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from glu.plots.evaluation import (
    READING_STYLE,
    STRATEGY_COLORS,
    STRATEGY_STYLE,
    plot_by_viewpoint,
    plot_differences,
    plot_early_recognition,
    plot_metric_vs_noise,
    plot_p_hmm_reliability,
    plot_reliability,
    plot_segment_readings,
    size_of_share,
    strategy_label,
)

PANEL = (3.9, 3.0)
"""Inches: the size of one panel."""


def _grid(nrows: int, ncols: int, height: float = PANEL[1]) -> tuple[Figure, list]:
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(PANEL[0] * ncols, height * nrows), layout="constrained", squeeze=False
    )
    return fig, list(axes.flat)


def strategy_legend(fig: Figure, strategies: Sequence[str], extra: Sequence = (), ncols: int = 4) -> None:
    """One legend above the panels: a line per strategy (and ``extra`` handles)."""
    handles = [
        Line2D(
            [],
            [],
            color=STRATEGY_COLORS.get(s, "black"),
            ls=STRATEGY_STYLE.get(s, "-"),
            marker="o",
            ms=3,
            label=strategy_label(s),
        )
        for s in strategies
    ]
    fig.legend(handles=[*handles, *extra], loc="outside upper center", ncols=ncols, fontsize=8, frameon=False)


def _drawn(table: pd.DataFrame, targets: Sequence[str]) -> list[str]:
    return list(dict.fromkeys(table[table.target.isin(targets)].strategy))


Cells = Sequence[Mapping[str, Any]]


def strategies_vs_noise_figure(results: pd.DataFrame, cells: Cells, fraction: float = 1.0) -> Figure:
    """Action accuracy (top) and effect log-loss (bottom) against the sensor noise, per cell of the design."""
    fig, axes = _grid(2, len(cells))
    for k, cell in enumerate(cells):
        plot_metric_vs_noise(axes[k], results, "action", "accuracy", fraction, where=cell)
        plot_metric_vs_noise(axes[len(cells) + k], results, "effect", "log_loss", fraction, where=cell)
    strategy_legend(fig, _drawn(results, ("action", "effect")))
    return fig


def early_recognition_figure(results: pd.DataFrame, cells: Cells) -> Figure:
    """Action accuracy (top) and effect log-loss (bottom) against the fraction of the gesture seen."""
    fig, axes = _grid(2, len(cells))
    for k, cell in enumerate(cells):
        plot_early_recognition(axes[k], results, "action", "accuracy", where=cell)
        plot_early_recognition(axes[len(cells) + k], results, "effect", "log_loss", where=cell)
    strategy_legend(fig, _drawn(results, ("action", "effect")))
    return fig


def calibration_figure(
    reliability: pd.DataFrame,
    results: pd.DataFrame,
    cells: Cells,
    fraction: float = 1.0,
    strategies: Sequence[str] = ("network", "hard", "virtual", "jeffrey", "true_action"),
    by_viewpoint: Sequence[str] = ("gesture", "network", "hard", "product"),
) -> Figure:
    """Reliability diagrams of the effect in the first two cells (top); the effect's ECE against noise and
    the action accuracy per viewpoint in the first cell (bottom). A key gives the marker sizes."""
    fig, axes = _grid(2, 2, height=3.2)
    for ax, cell in zip(axes[:2], cells[:2], strict=False):
        plot_reliability(ax, reliability, fraction, strategies=strategies, where=cell)
    plot_metric_vs_noise(axes[2], results, "effect", "ece", fraction, strategies=strategies, where=cells[0])
    plot_by_viewpoint(
        axes[3], results, "action", "accuracy", fraction, strategies=by_viewpoint, where=cells[0]
    )
    shown = list(dict.fromkeys([*strategies, *by_viewpoint]))
    sizes = [
        Line2D(
            [],
            [],
            marker="o",
            ls="none",
            color="0.5",
            alpha=0.7,
            ms=size_of_share(s) ** 0.5,
            label=f"{s:.0%} of the episodes in a bin",
        )
        for s in (0.05, 0.25, 0.5)
    ]
    strategy_legend(fig, [s for s in STRATEGY_COLORS if s in shown], sizes, ncols=5)
    return fig


def differences_figure(
    differences: pd.DataFrame,
    pairs: Sequence[tuple[str, str, str, str]],
    cells: Cells,
    fraction: float = 1.0,
) -> Figure:
    """Paired differences, one panel per cell of the design (stacked), with a key to colours and markers."""
    fig, axes = _grid(len(cells), 1, height=2.9)
    fig.set_figwidth(9.0)
    for ax, cell in zip(axes, cells, strict=True):
        plot_differences(ax, differences, pairs, fraction, where=cell)
    marks = [
        Line2D(
            [],
            [],
            marker="o",
            color="0.3",
            ls="none",
            label="filled: the interval excludes 0 on the better side",
        ),
        Line2D([], [], marker="o", color="0.3", mfc="white", ls="none", label="hollow: it does not"),
    ]
    strategy_legend(fig, list(dict.fromkeys(p[2] for p in pairs)), marks, ncols=3)
    return fig


def p_hmm_calibration_figure(
    reliability: pd.DataFrame,
    fraction: float = 1.0,
    where: Mapping[str, Any] | None = None,
    segments: pd.DataFrame | None = None,
) -> Figure:
    """p_HMM's own reliability on the corpus's held-out synthetic gestures, one line per reading (left), and,
    given the real segments' readings, p_HMM on each segment left out (right); one legend above."""
    fig, axes = _grid(1, 1 if segments is None else 2, height=3.4)
    plot_p_hmm_reliability(axes[0], reliability, fraction, where=where)
    handles = [
        Line2D([], [], color=c, ls=ls, marker="o", ms=3, label=f"p_HMM {reading}")
        for reading, (c, ls) in READING_STYLE.items()
    ]
    if segments is not None:
        plot_segment_readings(axes[1], segments)
        handles += axes[1].get_legend_handles_labels()[0]
    fig.legend(handles=handles, loc="outside upper center", ncols=3, fontsize=8, frameon=False)
    return fig
