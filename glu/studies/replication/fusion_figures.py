"""Figures of fusion: the soft-evidence sweeps, the tap thresholds, the fusion rules on the test gestures.

Every function draws on the axes it is given, first argument, and returns them: ``plot_x(ax, frame, …)``;
the frames are the tidy outputs of :mod:`glu.studies.replication.fusion`. The ``*_figure`` functions lay out
the notebooks' figures from them, one call each (e.g. :func:`soft_sweep_figure`, several sweeps side by side).
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from glu.plots.style import ACTION_COLORS, RULE_LINESTYLES, VALUE_COLORS, legend_right, new_figure, rule_label

NEAR_ZERO = 0.02
"""A sweep line that never rises above this lies on the axis; the title says which."""
SAME_P = 1e-6
"""Fusion strategies whose p differ by at most this on every segment are drawn as one bar."""


def plot_soft_sweep(ax: Axes, df: pd.DataFrame, legend: bool = True) -> Axes:
    """p_comb(target) against p_hmm(tap): one colour per value, one line style per rule.

    ``legend``: a legend right of the axes (colours: the values; line styles: the rules). Values that stay
    below :data:`NEAR_ZERO` under every rule are named in the title (their lines lie on the axis).
    """
    target = [c for c in df.columns if c not in ("evidence", "rule", "p_hmm_tap", "p")][0]
    for (rule, value), g in df.groupby(["rule", target], sort=False):
        color = VALUE_COLORS.get(value, ACTION_COLORS.get(value, "0.4"))
        ax.plot(g["p_hmm_tap"], g["p"], RULE_LINESTYLES.get(rule, "-"), color=color, lw=1.4)
    ax.set_xlabel(r"$p_{HMM}(tap)$ (rest split equally)")
    ax.set_ylabel(rf"$p_{{comb}}({target})$")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlim(0, 1)
    low = [str(v) for v, g in df.groupby(target, sort=False) if g["p"].max() < NEAR_ZERO]
    title = str(df["evidence"].iloc[0])
    if low:
        title += (
            f"\n{' and '.join(low)} stays below {NEAR_ZERO:g} under every rule (its lines lie along the axis)"
        )
    ax.set_title(title, fontsize=9)
    if legend:
        values = dict.fromkeys(df[target])
        rules = dict.fromkeys(df["rule"])
        handles = [
            Line2D(
                [], [], color=VALUE_COLORS.get(v, ACTION_COLORS.get(v, "0.4")), lw=3, label=f"{target} {v}"
            )
            for v in values
        ]
        handles += [
            Line2D([], [], color="0.3", ls=RULE_LINESTYLES.get(r, "-"), label=rule_label(r)) for r in rules
        ]
        legend_right(ax, handles=handles)
    return ax


def soft_sweep_figure(sweeps: Mapping[str, pd.DataFrame]) -> Figure:
    """The sweeps of p_HMM(tap) side by side (:func:`plot_soft_sweep`, one panel per sweep of ``sweeps``, in
    its order: e.g. :func:`glu.studies.replication.fusion.soft_evidence_sweeps`), the legend right of the
    last."""
    fig, axes = new_figure(len(sweeps), width=4.6)
    for k, (ax, sweep) in enumerate(zip(axes, sweeps.values(), strict=True)):
        plot_soft_sweep(ax, sweep, legend=k == len(sweeps) - 1)
    return fig


def tap_threshold_sweep_figure(sweep: pd.DataFrame, threshold: float) -> Figure:
    """Notebook 06's sweep: :func:`plot_soft_sweep` of ``sweep`` with the tap ``threshold`` (e.g.
    :func:`glu.studies.replication.fusion.tap_threshold`) as a dotted vertical line, labelled left of it
    "tap wins above <threshold>"."""
    fig, (ax,) = new_figure(1, width=6)
    plot_soft_sweep(ax, sweep)
    ax.axvline(threshold, color="0.3", linestyle=":", linewidth=1)
    ax.annotate(
        f"tap wins above {threshold:.4f}",
        (threshold, 0.9),
        xytext=(-5, 0),
        textcoords="offset points",
        ha="right",
        fontsize=8,
    )
    return fig


def plot_tap_thresholds(ax: Axes, df: pd.DataFrame) -> Axes:
    """The p_hmm(tap) above which tap wins, for each (Shape, Size, ObjVel): bars, values in a column right."""
    keys = [c for c in df.columns if c not in ("p_bn_tap", "threshold")]
    labels = [", ".join(str(r[c]) for c in keys) for _, r in df.iterrows()]
    y = np.arange(len(df))
    ax.barh(y, df["threshold"].fillna(0), color=ACTION_COLORS["tap"], edgecolor="0.2", linewidth=0.5)
    for yi, t in zip(y, df["threshold"], strict=True):
        text = "never" if np.isnan(t) else "any > 0" if t < 0.005 else f"{t:.3f}"
        ax.text(1.02, yi, text, va="center", fontsize=7, color="0.2", transform=ax.get_yaxis_transform())
    ax.axvline(1 / 3, color="0.4", linestyle=":", linewidth=1)
    ax.text(
        1 / 3, 1.01, "1/3: uniform $p_{HMM}$", transform=ax.get_xaxis_transform(), ha="center", fontsize=7
    )
    ax.set_yticks(y, labels, fontsize=7)
    ax.set_ylabel(", ".join(keys))
    ax.set_ylim(len(df) - 0.4, -0.6)
    ax.set_xlim(0, 1)
    ax.set_xlabel(r"$p_{HMM}(tap)$ needed for tap to win (never: it cannot)")
    return ax


def tap_thresholds_figure(thresholds: pd.DataFrame) -> Figure:
    """Notebook 06's thresholds: :func:`plot_tap_thresholds` of ``thresholds``
    (:func:`glu.studies.replication.fusion.tap_thresholds`), 5 × 5 inches."""
    fig, (ax,) = new_figure(1, width=5, height=5)
    plot_tap_thresholds(ax, thresholds)
    return fig


def plot_fusion_on_gestures(ax: Axes, df: pd.DataFrame, value: str = "fast", target: str = "ObjVel") -> Axes:
    """p_comb(target = value) per gesture segment, one bar per fusion strategy; HMM's top action below.

    Strategies that agree within :data:`SAME_P` on every segment share one bar, and the title says so.
    Every bar carries its value.
    """
    d = df[df[target] == value]
    segs = list(dict.fromkeys(zip(d["recording"], d["start"], d["end"], strict=True)))
    p = d.pivot_table(index=["recording", "start", "end"], columns="strategy", values="p", sort=False).loc[
        segs
    ]
    groups: list[list[str]] = []
    for st in dict.fromkeys(d["strategy"]):
        for grp in groups:
            if np.abs(p[st] - p[grp[0]]).max() <= SAME_P:
                grp.append(st)
                break
        else:
            groups.append([st])
    w = 0.8 / len(groups)
    hatches = ["", "//", ".."]
    for k, grp in enumerate(groups):
        x = np.arange(len(segs)) + (k - (len(groups) - 1) / 2) * w
        bars = ax.bar(
            x,
            p[grp[0]],
            width=w,
            color="#66C2A5",
            hatch=hatches[k % len(hatches)],
            edgecolor="0.2",
            linewidth=0.5,
            label=" = ".join(rule_label(s) for s in grp),
        )
        ax.bar_label(bars, fmt="%.3f", fontsize=7, padding=2)
    tops = (
        d.drop_duplicates(["recording", "start", "end"])
        .set_index(["recording", "start", "end"])
        .loc[segs, "hmm_top"]
    )
    ax.set_xticks(
        np.arange(len(segs)),
        [
            f"{textwrap.fill(r.replace('_', ' '), 16)}\n{a}–{b}\nHMM: {t}"
            for (r, a, b), t in zip(segs, tops, strict=True)
        ],
        fontsize=7,
    )
    ax.set_ylim(0, 1)
    ax.set_ylabel(rf"$p_{{comb}}({target}={value})$")
    title = str(d["evidence"].iloc[0])
    if len(groups) == 1 and len(groups[0]) > 1:
        names = ", ".join(rule_label(s) for s in groups[0])
        note = f"{names} give the same p on every segment (within {SAME_P:g})"
        hmm = [c for c in d.columns if c.startswith("p_hmm_")]
        if len(hmm) > 1:
            second = np.sort(d[hmm].to_numpy(dtype=float), axis=1)[:, -2].max()
            note += f": the other actions' p_HMM are at most {second:.0e}"
        title += "\n" + textwrap.fill(note, 90)
    ax.set_title(title, fontsize=9)
    if len(groups) > 1:
        legend_right(ax)
    return ax


def fusion_on_gestures_figure(df: pd.DataFrame, value: str = "fast", target: str = "ObjVel") -> Figure:
    """Notebook 04's figure: :func:`plot_fusion_on_gestures` of ``df``
    (:func:`glu.studies.replication.fusion.fusion_on_gestures`), 1.3 inches wide per gesture segment, 6 at
    least."""
    n = len(df[["recording", "start", "end"]].drop_duplicates())
    fig, (ax,) = new_figure(1, width=max(6, 1.3 * n))
    plot_fusion_on_gestures(ax, df, value=value, target=target)
    return fig
