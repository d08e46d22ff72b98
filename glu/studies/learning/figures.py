"""Figures of learning gestures from effects: learning curves, gaps to the true labels, the real person, what
the robot anticipates with the gestures it learned.

Each function draws a table of :mod:`glu.studies.learning.tables` or
:mod:`glu.studies.learning.real_person` (or the anticipation runs of
:func:`glu.studies.learning.learned_recognizers.anticipation_after_learning`) and returns the figure (or the
axes it was given).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

from glu.studies.anticipation.experiment import CASES, AnticipationRun
from glu.studies.anticipation.figures import plot_anticipation
from glu.studies.learning.tables import LEARNER_NAMES

LEARNER_STYLE: dict[str, dict] = {
    "true": dict(color="#222222", ls="-", marker="o"),
    "hard": dict(color="#C44E52", ls="-", marker="s"),
    "soft": dict(color="#4C72B0", ls="--", marker="^"),
    "confident": dict(color="#8172B3", ls="-.", marker="v"),
    "iterative": dict(color="#DD8452", ls=":", marker="D"),
    "random": dict(color="#8C8C8C", ls="-", marker="X"),
    "clustering": dict(color="#55A868", ls="--", marker="P"),
    "em": dict(color="#64B5CD", ls="-.", marker="*"),
    "unsupervised": dict(color="#A0A0A0", ls=":", marker="h"),
    "supervised_1": dict(color="#937860", ls=":", marker="<"),
    "supervised_5": dict(color="#937860", ls="--", marker=">"),
    "network": dict(color="#DA8BC3", ls=(0, (5, 2, 1, 2)), marker=""),
    "always_tap": dict(color="#BBBBBB", ls="-", marker=""),
}
"""Each learner's colour, line and marker: told apart by more than their hue."""
CURVE_LEARNERS: tuple[str, ...] = ("true", "hard", "soft", "random", "clustering", "supervised_5", "network")
"""The learners of the learning-curve panels (every learner is in the tables and in the gaps figure)."""
CHANCE = "chance (1 in 3)"


def _label(learner: str) -> str:
    return LEARNER_NAMES.get(learner, learner)


def _episodes_axis(ax: Axes, ticks: Sequence[int]) -> None:
    """A log axis of episodes labelled at every checkpoint that fits (10, 100, 1,000 …, with 20 and 50
    between when there is room)."""
    ax.set_xscale("log")
    ticks = sorted(int(t) for t in ticks)
    decades = [t for t in ticks if np.log10(t).is_integer()]
    shown = ticks if len(ticks) <= 6 else decades or ticks
    ax.xaxis.set_major_locator(FixedLocator(shown))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}"))
    ax.xaxis.set_minor_locator(FixedLocator([t for t in ticks if t not in shown]))
    ax.xaxis.set_minor_formatter(FuncFormatter(lambda v, _: ""))


def _where(ambiguity: str, words: bool | None) -> str:
    amb = ambiguity.replace("_", " ")
    return f"{amb}, {'with' if words else 'without'} words"


def plot_learning_curves(
    ax: Axes,
    curves: pd.DataFrame,
    world: str,
    ambiguity: str,
    words: bool,
    learners: Sequence[str] = CURVE_LEARNERS,
) -> Axes:
    """Held-out accuracy against episodes seen (log scale) of each learner in one world, ambiguity and
    words; each checkpoint's 95 % interval as a vertical line (learners nudged apart sideways)."""
    c = curves[curves["world"] == world]
    shown = [lr for lr in learners if (c["learner"] == lr).any()]
    for j, lr in enumerate(shown):
        sel = c["learner"] == lr
        if lr not in ("true", "unsupervised") and not lr.startswith("supervised_"):
            sel &= (c["ambiguity"] == ambiguity) & (c["words"].astype(object) == words)
        g = c[sel].sort_values("episodes")
        if g.empty:
            continue
        st = LEARNER_STYLE.get(lr, dict(color="black", ls="-", marker="o"))
        x = g["episodes"].to_numpy(dtype=float) * 1.06 ** (j - (len(shown) - 1) / 2)
        ax.plot(
            x,
            g["accuracy"],
            color=st["color"],
            ls=st["ls"],
            marker=st["marker"],
            ms=4,
            lw=1.3,
            label=_label(lr),
        )
        ax.vlines(x, g["ci_low"], g["ci_high"], color=st["color"], lw=0.8, alpha=0.7)
    ax.axhline(1 / 3, color="0.55", lw=0.8, ls=":", label=CHANCE)
    _episodes_axis(ax, sorted(c["episodes"].unique()))
    ax.set_ylim(-0.02, 1.02)
    ax.set_ylabel("held-out accuracy")
    ax.set_title(f"{world} world: {_where(ambiguity, words)}", fontsize=9)
    ax.grid(alpha=0.3)
    return ax


def _legend_above(fig: Figure, ax: Axes, ncols: int = 4) -> None:
    """The legend of ``ax``'s labelled artists, once, above the figure's panels (never on the data)."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncols=ncols, fontsize=7, frameon=False)


def learning_curves_figure(curves: pd.DataFrame, ambiguity: str = "mixed") -> Figure:
    """The learning curves in one ambiguity: a row per world, without and with words, one legend above."""
    worlds = list(dict.fromkeys(curves["world"]))
    fig, axes = plt.subplots(
        len(worlds), 2, figsize=(9, 2.8 * len(worlds) + 0.9), squeeze=False, sharex=True, layout="constrained"
    )
    for i, world in enumerate(worlds):
        for j, words in enumerate((False, True)):
            plot_learning_curves(axes[i, j], curves, world, ambiguity, words)
            axes[i, j].set_xlabel("episodes seen" if i == len(worlds) - 1 else "")
            if j:
                axes[i, j].set_ylabel("")
    _legend_above(fig, axes[0, 0], ncols=4)
    return fig


GAP_LEARNERS: tuple[str, ...] = ("hard", "soft", "confident", "iterative", "random", "clustering", "em")


def plot_gaps(ax: Axes, budgets: pd.DataFrame, world: str, words: bool, budget: int, margin: float) -> Axes:
    """Each learner's gap to the true labels in each ambiguity (one row each), with its 90 % interval, the
    equivalence margin shaded: a filled marker where the learner matches the true labels (equivalent),
    hollow where it does not."""
    b = budgets[(budgets["world"] == world) & (budgets["budget"] == budget)]
    rows = b[b["words"].astype(object).eq(words) & b["learner"].isin(GAP_LEARNERS)]
    ambs = list(dict.fromkeys(rows["ambiguity"]))
    base = b[b["learner"].isin(["supervised_1", "supervised_5", "unsupervised"])]
    groups = [("baselines", base)] + [(a, rows[rows["ambiguity"] == a]) for a in ambs]
    y, ticks, labels = 0.0, [], []
    for name, g in groups:
        n = len(g)
        for k, r in enumerate(g.itertuples()):
            yy = y + k / max(n, 1)
            st = LEARNER_STYLE.get(r.learner, dict(color="black", marker="o"))
            ax.hlines(yy, r.gap_low90, r.gap_high90, color=st["color"], lw=1.2)
            ax.plot(
                [r.gap],
                [yy],
                ls="none",
                marker=st["marker"] or "o",
                ms=5,
                color=st["color"],
                mfc=st["color"] if r.equivalent else "white",
            )
        ticks.append(y + 0.5 * (n - 1) / max(n, 1))
        labels.append(name.replace("_", " "))
        y += 1.4
    ax.axvspan(-margin, margin, color="0.85", lw=0, zorder=0)
    ax.axvline(0, color="0.4", lw=0.8)
    ax.yaxis.set_major_locator(FixedLocator(ticks))
    ax.set_yticklabels(labels, fontsize=7)
    ax.yaxis.set_minor_locator(NullLocator())
    ax.invert_yaxis()
    ax.set_xlabel("accuracy − the true labels' (90 % interval)")
    ax.set_title(f"{world} world, {'with' if words else 'without'} words, {budget:,} episodes", fontsize=9)
    ax.grid(alpha=0.3, axis="x")
    return ax


def gaps_figure(budgets: pd.DataFrame, budget: int | None = None) -> Figure:
    """The gaps to the true labels at one budget (default: the largest): a row per world, without and with
    words, one legend above."""
    budget = int(budget or budgets["budget"].max())
    margin = float(budgets["margin"].iloc[0])
    worlds = list(dict.fromkeys(budgets["world"]))
    fig, axes = plt.subplots(
        len(worlds), 2, figsize=(10, 4.2 * len(worlds) + 0.9), squeeze=False, layout="constrained"
    )
    for i, world in enumerate(worlds):
        for j, words in enumerate((False, True)):
            plot_gaps(axes[i, j], budgets, world, words, budget, margin)
    ax = axes[0, 0]
    for lr in GAP_LEARNERS + ("supervised_1", "supervised_5", "unsupervised"):
        st = LEARNER_STYLE[lr]
        ax.plot([], [], ls="none", marker=st["marker"], color=st["color"], label=_label(lr))
    ax.plot([], [], ls="none", marker="o", color="0.3", mfc="white", label="hollow: not shown equivalent")
    ax.fill_between([], [], color="0.85", label=f"equivalence margin ±{margin:g}")
    _legend_above(fig, ax, ncols=4)
    return fig


def plot_real_person(ax: Axes, summary: pd.DataFrame, study: str, features: str) -> Axes:
    """Each learner's accuracy on the person's held-out segments: a bar (hatched: with words; a mark on the
    axis where it is 0) with its 95 % interval (draws and segments resampled)."""
    s = summary[(summary["study"] == study) & (summary["features"] == features)].reset_index(drop=True)
    colors = [LEARNER_STYLE.get(lr, dict(color="black"))["color"] for lr in s["learner"]]
    x = np.arange(len(s))
    # one set of bars, each named on the axis below it (its colour only repeats the name)
    bars = ax.bar(x, s["accuracy"], color=colors, edgecolor="0.2", linewidth=0.6, alpha=0.85)
    for bar, words in zip(bars.patches, s["words"], strict=True):
        if words is True:
            bar.set_hatch("///")
    for i, r in s.iterrows():
        if r["accuracy"] == 0:
            ax.plot([i], [0.005], marker="_", ms=14, mew=2, color=colors[i])
    ax.vlines(x, s["ci_low"], s["ci_high"], color="0.1", lw=1.2)
    names = [
        SHORT.get(lr, _label(lr)) + (" + words" if w is True else "")
        for lr, w in zip(s["learner"], s["words"], strict=True)
    ]
    ax.set_xticks(np.arange(len(s)))
    ax.set_xticklabels(names, rotation=40, ha="right", fontsize=7)
    ax.set_ylim(0, 1.05)
    ax.axhline(1 / 3, color="0.55", lw=0.8, ls=":", label=CHANCE)
    ax.set_ylabel("accuracy on the real segments")
    where = (
        "generator fitted to the person,\nleave-one-segment-out,"
        if study == "fitted"
        else "glu's generator,\n"
    )
    ax.set_title(f"{where} {features} features", fontsize=9)
    return ax


SHORT = {"random": "random labels", "clustering": "clusters named by network"}


def real_person_figure(summary: pd.DataFrame) -> Figure:
    """The real person: the fitted generator (leave-one-segment-out) and glu's standard generator (raw and
    study features); bars are accuracies over the segments and draws, lines their 95 % intervals."""
    panels = list(dict.fromkeys(zip(summary["study"], summary["features"], strict=True)))
    widths = [int(((summary["study"] == st) & (summary["features"] == f)).sum()) for st, f in panels]
    fig, axes = plt.subplots(
        1,
        len(panels),
        figsize=(2.2 + 0.42 * sum(widths), 4.4),
        squeeze=False,
        layout="constrained",
        width_ratios=widths,
        sharey=True,
    )
    for ax, (study, features) in zip(axes[0], panels, strict=True):
        plot_real_person(ax, summary, study, features)
    for ax in axes[0, 1:]:
        ax.set_ylabel("")
    draws, segs = int(summary["draws"].iloc[0]), int(summary["segments"].iloc[0])
    ax = axes[0, 0]
    ax.plot(
        [], [], color="0.1", lw=1.2, label=f"95 % interval ({segs} segments × {draws} draws, both resampled)"
    )
    _legend_above(fig, ax, ncols=2)
    return fig


def learned_anticipation_figure(runs: Mapping[tuple[str, str], AnticipationRun], hmms: str) -> Figure:
    """What the robot anticipates with the HMMs ``hmms`` (TCDS Fig. 5's cases that ``runs`` holds, one column
    each, in the order of :data:`~glu.studies.anticipation.experiment.CASES`:
    :func:`~glu.studies.anticipation.figures.plot_anticipation`), from the runs keyed by (hmms, case) of
    :func:`~glu.studies.learning.learned_recognizers.anticipation_after_learning`."""
    cases = [case for case in CASES if (hmms, case) in runs]
    fig, axes = plt.subplots(2, len(cases), figsize=(5 * len(cases), 5.5), sharex="col", squeeze=False)
    for j, case in enumerate(cases):
        run = runs[hmms, case]
        plot_anticipation(axes[:, j], run.curves(), run.predictions())
    return fig
