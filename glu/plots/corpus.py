"""The figures of the corpus evaluation, whole: panels of :mod:`glu.plots.evaluation` and one legend each.

Each function takes the sweep's tables (:mod:`glu.sweep`) and returns a laid-out figure (constrained
layout; the legend above the panels, naming every strategy drawn once). The panels are two columns wide,
one per way of reading p_HMM (:data:`glu.experiments.corpus.POSTERIORS`), to fit a page.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib.pyplot as plt
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from glu.plots.evaluation import (
    STRATEGY_COLORS,
    STRATEGY_STYLE,
    plot_by_viewpoint,
    plot_differences,
    plot_early_recognition,
    plot_metric_vs_noise,
    plot_reliability,
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


def strategies_vs_noise_figure(
    results: pd.DataFrame, posteriors: Sequence[str], fraction: float = 1.0
) -> Figure:
    """Action accuracy (top) and effect log-loss (bottom) against the sensor noise, per reading of p_HMM."""
    fig, axes = _grid(2, len(posteriors))
    for k, post in enumerate(posteriors):
        plot_metric_vs_noise(axes[k], results, "action", "accuracy", fraction, posterior=post)
        plot_metric_vs_noise(
            axes[len(posteriors) + k], results, "effect", "log_loss", fraction, posterior=post
        )
    strategy_legend(fig, _drawn(results, ("action", "effect")))
    return fig


def early_recognition_figure(results: pd.DataFrame, posteriors: Sequence[str]) -> Figure:
    """Action accuracy (top) and effect log-loss (bottom) against the fraction of the gesture seen."""
    fig, axes = _grid(2, len(posteriors))
    for k, post in enumerate(posteriors):
        plot_early_recognition(axes[k], results, "action", "accuracy", posterior=post)
        plot_early_recognition(axes[len(posteriors) + k], results, "effect", "log_loss", posterior=post)
    strategy_legend(fig, _drawn(results, ("action", "effect")))
    return fig


def calibration_figure(
    reliability: pd.DataFrame,
    results: pd.DataFrame,
    posteriors: Sequence[str],
    fraction: float = 1.0,
    strategies: Sequence[str] = ("network", "hard", "virtual", "jeffrey", "true_action"),
    by_viewpoint: Sequence[str] = ("gesture", "network", "hard", "product"),
) -> Figure:
    """Reliability diagrams of the effect per way of reading p_HMM (top); the effect's ECE against noise
    and the action accuracy per viewpoint, with the last way (bottom). A key gives the marker sizes."""
    fig, axes = _grid(2, 2, height=3.2)
    for ax, post in zip(axes[:2], posteriors[:2], strict=False):
        plot_reliability(ax, reliability, fraction, strategies=strategies, posterior=post)
    plot_metric_vs_noise(
        axes[2], results, "effect", "ece", fraction, strategies=strategies, posterior=posteriors[-1]
    )
    plot_by_viewpoint(
        axes[3], results, "action", "accuracy", fraction, strategies=by_viewpoint, posterior=posteriors[-1]
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
    posteriors: Sequence[str],
    fraction: float = 1.0,
) -> Figure:
    """Paired differences, one panel per way of reading p_HMM (stacked), with a key to colours and markers."""
    fig, axes = _grid(len(posteriors), 1, height=2.9)
    fig.set_figwidth(9.0)
    for ax, post in zip(axes, posteriors, strict=True):
        plot_differences(ax, differences, pairs, fraction, posterior=post)
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
