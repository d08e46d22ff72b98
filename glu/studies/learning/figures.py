"""Figures of learning gestures from effects: learning curves with intervals, episodes to match, real
gestures.

Each function draws a table of :mod:`glu.studies.learning.study` or
:mod:`glu.studies.learning.self_supervised` on the axes it is given and returns them.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

LEARNER_COLORS = {
    "hard": "#C44E52",
    "soft": "#4C72B0",
    "confident": "#8172B3",
    "iterative": "#DD8452",
    "true": "#222222",
    "unsupervised": "#8C8C8C",
    "network": "#937860",
}
LEARNER_STYLE = {"true": ":", "unsupervised": "--", "network": "-."}
LEARNER_LABEL = {
    "true": "true labels",
    "unsupervised": "unsupervised",
    "network": "network alone (no gesture)",
}


def _rows(curves: pd.DataFrame, learner: str, ambiguity: str, words: bool) -> pd.DataFrame:
    if learner in ("true", "unsupervised"):
        sel = curves["learner"] == learner
    else:
        sel = (curves["learner"] == learner) & (curves["ambiguity"] == ambiguity) & (curves["words"] == words)
    return curves[sel].sort_values("episodes")


def plot_learning_curves(
    ax: Axes,
    curves: pd.DataFrame,
    ambiguity: str,
    words: bool,
    learners: Sequence[str] = ("hard", "soft", "confident", "iterative", "true", "unsupervised", "network"),
) -> Axes:
    """Held-out accuracy against episodes seen (log scale) of each learner in one ambiguity, with or
    without words, with its interval as a band; the network alone as a flat line."""
    for lr in learners:
        g = _rows(curves, lr, ambiguity, words)
        if g.empty:
            continue
        c = LEARNER_COLORS.get(lr, "black")
        x = g["episodes"].to_numpy(dtype=float)
        ax.plot(
            x,
            g["accuracy"],
            color=c,
            ls=LEARNER_STYLE.get(lr, "-"),
            marker="" if lr == "network" else "o",
            ms=3,
            lw=1.3,
            label=LEARNER_LABEL.get(lr, lr),
        )
        ax.fill_between(x, g["ci_low"], g["ci_high"], color=c, alpha=0.12 if lr != "network" else 0.06, lw=0)
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    ax.axhline(1 / 3, color="0.7", lw=0.6, ls=":")
    ax.set_xlabel("episodes seen")
    ax.set_ylabel("held-out accuracy")
    ax.set_title(f"{ambiguity}, {'with' if words else 'without'} words", fontsize=9)
    ax.grid(alpha=0.3)
    return ax


def plot_episodes_to_match(ax: Axes, match: pd.DataFrame, schemes: Sequence[str] | None = None) -> Axes:
    """For each scheme (colour) and condition (ambiguity × words, rows): how many episodes until the
    learned HMMs match the true-label HMMs within the interval; a cross at the right edge where they never
    do by the last checkpoint."""
    m = match[match["learner"] != "unsupervised"]
    schemes = list(schemes or dict.fromkeys(m["learner"]))
    conditions = list(dict.fromkeys(zip(m["ambiguity"], m["words"], strict=True)))
    last = float(m["last_episodes"].max())
    for lr in schemes:  # the legend: one entry per scheme, matched or not
        ax.plot([], [], marker="o", color=LEARNER_COLORS.get(lr, "black"), ms=4, ls="none", label=lr)
    for i, (amb, words) in enumerate(conditions):
        for j, lr in enumerate(schemes):
            row = m[(m["learner"] == lr) & (m["ambiguity"] == amb) & (m["words"] == words)]
            if row.empty:
                continue
            y = i + (j - (len(schemes) - 1) / 2) * 0.15
            n = row["episodes_to_match"].iloc[0]
            c = LEARNER_COLORS.get(lr, "black")
            if np.isnan(n):
                ax.plot([last * 1.6], [y], marker="x", color=c, ms=5, ls="none")
            else:
                ax.plot([n], [y], marker="o", color=c, ms=4, ls="none")
    ax.set_xscale("log")
    ax.set_yticks(range(len(conditions)))
    ax.set_yticklabels([f"{a}, {'words' if w else 'no words'}" for a, w in conditions], fontsize=7)
    ax.axvline(last, color="0.6", lw=0.8, ls=":")
    ax.set_xlabel("episodes until the learned HMMs match the true-label ones (× : not by the last)")
    ax.invert_yaxis()
    ax.grid(alpha=0.3, axis="x")
    return ax


def plot_real_gestures(ax: Axes, summary: pd.DataFrame, test: str = "loso") -> Axes:
    """Accuracy on the real gestures of each learner (bars: mean over draws; lines: min–max over draws),
    and the network's label accuracy (marks)."""
    s = summary[summary["test"] == test].reset_index(drop=True)
    x = np.arange(len(s))
    colors = [LEARNER_COLORS.get(lr, "black") for lr in s["learner"]]
    ax.bar(x, s["accuracy"], color=colors, edgecolor="0.2", linewidth=0.6)
    ax.vlines(x, s["accuracy_min"], s["accuracy_max"], color="0.15", lw=1.2)
    labelled = ~s["learner"].isin(["true", "unsupervised"])
    ax.plot(
        x[labelled],
        s["label_accuracy"][labelled],
        marker="_",
        color="black",
        ms=14,
        mew=2,
        ls="none",
        label="the network's labels",
    )
    ax.set_xticks(x)
    ax.set_xticklabels(s["learner"], rotation=30, fontsize=8)
    ax.set_ylim(0, 1.05)
    ax.axhline(1 / 3, color="0.7", lw=0.6, ls=":")
    ax.set_ylabel("accuracy")
    ax.set_title("leave-one-segment-out, standing" if test == "loso" else "the two seated taps", fontsize=9)
    return ax


def _legend_above(fig: Figure, ax: Axes, ncols: int = 4) -> None:
    """The legend of ``ax``'s labelled artists, once, above the figure's panels (never on the data)."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncols=ncols, fontsize=7, frameon=False)


def learning_curves_figure(curves: pd.DataFrame, ambiguities: Sequence[str]) -> Figure:
    """The learning curves: one row per ambiguity, without and with words, one legend above."""
    size = (8, 2.3 * len(ambiguities) + 0.6)
    fig, axes = plt.subplots(
        len(ambiguities), 2, figsize=size, squeeze=False, sharex=True, layout="constrained"
    )
    for i, amb in enumerate(ambiguities):
        for j, words in enumerate((False, True)):
            plot_learning_curves(axes[i, j], curves, amb, words)
            axes[i, j].set_xlabel("episodes seen" if i == len(ambiguities) - 1 else "")
    _legend_above(fig, axes[0, 0])
    return fig


def episodes_to_match_figure(match: pd.DataFrame) -> Figure:
    """Episodes until each scheme matches the true labels, per condition, one legend above."""
    m = match[match["learner"] != "unsupervised"]
    n = len(set(zip(m["ambiguity"], m["words"], strict=True)))
    fig, ax = plt.subplots(figsize=(8, 0.35 * n + 1.6), layout="constrained")
    plot_episodes_to_match(ax, match)
    _legend_above(fig, ax, ncols=5)
    return fig


def real_gestures_figure(summary: pd.DataFrame) -> Figure:
    """The real gestures, labels hidden: leave-one-segment-out (left) and the seated taps (right)."""
    fig, axes = plt.subplots(1, 2, figsize=(9.2, 3.6), layout="constrained")
    plot_real_gestures(axes[0], summary, "loso")
    plot_real_gestures(axes[1], summary, "seated")
    _legend_above(fig, axes[0], ncols=2)
    return fig
