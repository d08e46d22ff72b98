"""Figures of the Affordance–Words network: the papers' bar charts, the learned structure, the unseen rows.

Every function draws on the axes it is given, first argument (a sequence of axes for multi-panel
figures), and returns them: ``plot_x(ax, frame, …)``. Frames are the tidy outputs of
:mod:`glu.studies.replication.fusion`; where they hold the original model's values (``p_original``), those are
drawn beside ours: black marks on single bars, a narrow outlined bar beside a stacked one.
The ``*_figure`` functions lay out the notebooks' figures from them, one call each (e.g.
:func:`effect_vs_rules_figure`, the effect under each soft-evidence rule).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from glu.plots.style import (
    ACTION_COLORS,
    ORIGINAL_LABEL,
    ORIGINAL_MARK,
    VALUE_COLORS,
    bars_with_original,
    legend_right,
    new_figure,
    rule_label,
)

ORIGINAL_BAR = {"edgecolor": "black", "lw": 0.8, "hatch": "////"}
"""The original model's stacked bar, drawn narrow beside ours."""
SAME_DELTA = 1e-9
"""Two Δp(w) lists this close (max ``|difference|``) are one list: the figure says so instead of drawing
both."""


def _hmm_rows(cases: Sequence[str]) -> list[str]:
    return [c.replace("no action evidence", "none") for c in cases]


def plot_effect_prediction(axes: Sequence[Axes], df: pd.DataFrame) -> Sequence[Axes]:
    """GLU 2017 Fig. 4: bars of p(ObjVel | Action=tap, Shape, Size), one axis per case, values on the bars."""
    for ax, (case, g) in zip(axes, df.groupby("case", sort=False), strict=False):
        x = np.arange(len(g))
        orig = g["p_original"].to_numpy() if "p_original" in g else None
        bars_with_original(ax, x, g["p"].to_numpy(), [VALUE_COLORS.get(v, "0.6") for v in g["ObjVel"]], orig)
        for xi, p in zip(x, g["p"], strict=True):
            ax.annotate(
                f"{p:.3f}" if p >= 5e-4 else f"{p:.0e}",
                (xi, p),
                xytext=(0, 6),
                textcoords="offset points",
                ha="center",
                fontsize=8,
            )
        ax.set_xticks(x, g["ObjVel"])
        ax.set_ylim(0, 1.13)  # room for the value above a bar of 1
        ax.set_yticks(np.linspace(0, 1, 6))
        ax.set_xlabel("ObjVel")
        ax.set_ylabel("probability")
        ax.set_title(f"tap on a {case}", fontsize=10)
    if "p_original" in df:
        legend_right(axes[-1])
    return axes


def effect_prediction_figure(df: pd.DataFrame) -> Figure:
    """GLU 2017 Fig. 4 as notebook 07 draws it: :func:`plot_effect_prediction` of ``df``
    (:func:`glu.studies.replication.fusion.effect_prediction`), a panel per case side by side."""
    fig, axes = new_figure(df["case"].nunique())
    plot_effect_prediction(axes, df)
    return fig


def plot_word_change(ax: Axes, df: pd.DataFrame, other: pd.DataFrame | None = None) -> Axes:
    """GLU 2017 Fig. 5: Δp(w) for the words whose probability changes by more than the threshold.

    ``other``: the same change under other evidence (the original code's, with Color=yellow). When its
    Δp(w) equal ``df``'s within :data:`SAME_DELTA` the title says so; otherwise its bars are drawn beside.
    """
    g = df[df["shown"]]
    x = np.arange(len(g))
    colors = np.where(g["delta"] > 0, "#DD8452", "#4C72B0")
    ev = df.attrs.get("parameters", {}).get("evidence") or {}
    same = other is not None and _same_delta(df, other)
    width = 0.8 if other is None or same else 0.4
    shift = 0.0 if width == 0.8 else -0.2
    ax.bar(x + shift, g["delta"], width=width, color=colors, edgecolor="0.2", linewidth=0.6)
    if other is not None and not same:
        h = other.set_index("word").loc[g["word"]]
        ax.bar(
            x + 0.2,
            h["delta"],
            width=0.4,
            color=colors,
            edgecolor="0.2",
            lw=0.6,
            hatch="//",
            label=_given(other),
        )
    if "delta_original" in g:
        ax.plot(
            x + shift,
            g["delta_original"],
            **{**ORIGINAL_MARK, "markersize": 20 * width},
            label=ORIGINAL_LABEL,
        )
    ax.axhline(0, color="0.2", linewidth=0.8)
    ax.set_xticks(x, g["word"], rotation=60, ha="right")
    ax.set_ylabel(r"$\Delta p(w)$")
    title = r"$p(w \mid F, E, A{=}tap) - p(w \mid F, E)$" + f"\nF, E = {_given(df)}"
    title += " (as the original code)" if "Color" in ev else " (as the paper's text)"
    if same:
        gap = float(np.abs(df.set_index("word")["delta"] - other.set_index("word")["delta"]).max())
        extra = {
            k: v for k, v in (other.attrs.get("parameters", {}).get("evidence") or {}).items() if k not in ev
        }
        added = ", ".join(f"{k}={v}" for k, v in extra.items()) or "the other evidence"
        title += (
            f"\nadding {added} (as the original code) changes no Δp(w) by more than {max(gap, 1e-16):.0e}"
        )
    ax.set_title(title, fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        legend_right(ax)
    return ax


def word_change_figure(df: pd.DataFrame, other: pd.DataFrame | None = None) -> Figure:
    """GLU 2017 Fig. 5 as notebook 07 draws it: :func:`plot_word_change` of ``df`` (and ``other``), 7 × 3.6
    inches."""
    fig, (ax,) = new_figure(1, width=7, height=3.6)
    plot_word_change(ax, df, other=other)
    return fig


def _given(df: pd.DataFrame) -> str:
    ev = df.attrs.get("parameters", {}).get("evidence") or {}
    return ", ".join(f"{k}={v}" for k, v in ev.items()) or str(df["evidence"].iloc[0])


def _same_delta(a: pd.DataFrame, b: pd.DataFrame) -> bool:
    x, y = a.set_index("word")["delta"], b.set_index("word")["delta"]
    return set(x.index) == set(y.index) and float(np.abs(x - y.loc[x.index]).max()) <= SAME_DELTA


def plot_action_vs_soft_evidence(ax: Axes, df: pd.DataFrame, threshold: float | None = None) -> Axes:
    """TCDS: p_comb(Action | evidence) as grouped bars, one group per p_hmm row."""
    cases = list(dict.fromkeys(df["case"]))
    actions = list(dict.fromkeys(df["Action"]))
    w = 0.8 / len(actions)
    for k, a in enumerate(actions):
        g = df[df["Action"] == a].set_index("case").loc[cases]
        x = np.arange(len(cases)) + (k - (len(actions) - 1) / 2) * w
        ax.bar(x, g["p"], width=w, color=ACTION_COLORS.get(a, "0.6"), label=a, edgecolor="0.2", linewidth=0.5)
        if "p_original" in g:
            label = ORIGINAL_LABEL if k == 0 else None
            ax.plot(x, g["p_original"], **{**ORIGINAL_MARK, "markersize": 6}, label=label)
    ax.set_xticks(np.arange(len(cases)), _hmm_rows(cases), rotation=30, ha="right", fontsize=8)
    ax.set_xlabel(r"$p_{HMM}$ [grasp tap touch]")
    ax.set_ylabel(r"$p_{comb}(Action)$")
    ax.set_ylim(0, 1)
    title = "action given soft evidence (product rule)"
    if threshold is not None and np.isfinite(threshold):
        title += f": tap wins for $p_{{HMM}}(tap) > {threshold:.4f}$"
    ax.set_title(title, fontsize=9)
    legend_right(ax)
    return ax


def action_vs_soft_evidence_figure(df: pd.DataFrame, threshold: float | None = None) -> Figure:
    """TCDS's action under soft evidence as notebook 08 draws it: :func:`plot_action_vs_soft_evidence` of
    ``df`` (:func:`glu.studies.replication.fusion.action_vs_soft_evidence`), its title giving the tap
    ``threshold``; 7 inches wide."""
    fig, (ax,) = new_figure(1, width=7)
    plot_action_vs_soft_evidence(ax, df, threshold)
    return fig


def plot_effect_vs_soft_evidence(
    axes: Sequence[Axes], df: pd.DataFrame, rule: str = "virtual", legend: bool = True
) -> Sequence[Axes]:
    """TCDS: p_comb(ObjVel | Shape) stacked per p_hmm row, one axis per shape.

    With the original model's values (``p_original``), its stack is a narrow outlined bar right of ours.
    ``legend``: draw the legend right of the last axis (once per figure).
    """
    d = df[df["rule"] == rule]
    has_original = "p_original" in d
    width, ours_x, theirs_x = (0.55, -0.13, 0.27) if has_original else (0.8, 0.0, 0.0)
    for ax, (shape, g) in zip(axes, d.groupby("Shape", sort=False), strict=False):
        cases = list(dict.fromkeys(g["case"]))
        x = np.arange(len(cases))
        stacks = {"p": np.zeros(len(cases)), "p_original": np.zeros(len(cases))}
        for v in dict.fromkeys(g["ObjVel"]):
            rows = g[g["ObjVel"] == v].set_index("case").loc[cases]
            c = VALUE_COLORS.get(v, "0.6")
            ax.bar(x + ours_x, rows["p"], width, bottom=stacks["p"], color=c, edgecolor="0.2", linewidth=0.5)
            stacks["p"] += rows["p"].to_numpy()
            if has_original:
                p = rows["p_original"].to_numpy()
                ax.bar(x + theirs_x, p, 0.2, bottom=stacks["p_original"], color=c, **ORIGINAL_BAR)
                stacks["p_original"] += p
        ax.set_xticks(x, _hmm_rows(cases), rotation=30, ha="right", fontsize=8)
        ax.set_xlim(-0.6, len(cases) - 0.4)
        ax.set_ylim(0, 1)
        ax.set_ylabel(r"$p_{comb}(ObjVel)$")
        ax.set_xlabel(r"$p_{HMM}$ [grasp tap touch]")
        ax.set_title(f"{shape}, {rule_label(rule)}", fontsize=10)
    if legend:
        handles = [
            Patch(facecolor=VALUE_COLORS.get(v, "0.6"), edgecolor="0.2", label=v)
            for v in dict.fromkeys(d["ObjVel"])
        ]
        if has_original:
            handles += [
                Patch(facecolor="white", edgecolor="0.2", label="glu, wide"),
                Patch(facecolor="white", **ORIGINAL_BAR, label=f"{ORIGINAL_LABEL}, narrow"),
            ]
        axes[-1].legend(
            handles=handles,
            fontsize=8,
            frameon=False,
            title="ObjVel",
            title_fontsize=8,
            loc="center left",
            bbox_to_anchor=(1.02, 0.5),
        )
    return axes


def effect_vs_soft_evidence_figure(df: pd.DataFrame, rule: str = "virtual") -> Figure:
    """TCDS's effect under soft evidence as notebook 08 draws it: :func:`plot_effect_vs_soft_evidence` of
    ``df``'s rows of ``rule``, a panel per shape side by side, the legend right of the last (notebook 05's
    figure of several rules is :func:`effect_vs_rules_figure`)."""
    fig, axes = new_figure(df.loc[df["rule"] == rule, "Shape"].nunique())
    plot_effect_vs_soft_evidence(axes, df, rule=rule)
    return fig


def effect_vs_rules_figure(df: pd.DataFrame, rules: Sequence[str] = ("virtual", "jeffrey")) -> Figure:
    """TCDS effect prediction under each soft-evidence rule: a row of :func:`plot_effect_vs_soft_evidence`
    per rule (in the order given), a column per shape, the rows sharing their x axis; one legend, right of
    the last row."""
    shapes = list(dict.fromkeys(df["Shape"]))
    fig, axes = new_figure(len(shapes), width=3.8, height=3.4, nrows=len(rules), sharex=True)
    for k, rule in enumerate(rules):
        row = axes[k * len(shapes) : (k + 1) * len(shapes)]
        plot_effect_vs_soft_evidence(row, df, rule=rule, legend=k == len(rules) - 1)
    return fig


def plot_unseen_rows(ax: Axes, df: pd.DataFrame, tolerance: float = 1e-3) -> Axes:
    """The original's all-zero rows vs uniform rows: the same numbers under both models, y = x where equal.
    Each experiment its colour and its marker (not told apart by colour alone)."""
    colors = ["#4C72B0", "#DD8452", "#55A868", "#C44E52", "#8172B3"]
    markers = ["o", "s", "^", "D", "v"]
    for k, (name, g) in enumerate(df.groupby("experiment", sort=False)):
        style = dict(color=colors[k % len(colors)], marker=markers[k % len(markers)])
        ax.scatter(g["p_zero"], g["p_uniform"], s=14, label=name, alpha=0.8, **style)
    lo = min(df["p_zero"].min(), df["p_uniform"].min())
    ax.plot([lo, 1], [lo, 1], color="0.5", linewidth=0.8, label="y = x (no change)", zorder=0)
    ax.set_xlabel("original: all-zero rows (faithful)")
    ax.set_ylabel("corrected: uniform rows")
    worst = df.loc[df["uniform_minus_zero"].abs().idxmax()]
    moved = int((df["uniform_minus_zero"].abs() > tolerance).sum())
    where = f"{worst['experiment']}, {worst['case']}" if "case" in df else str(worst["experiment"])
    ax.set_title(
        f"uniform rows move {moved} of {len(df)} numbers by more than {tolerance:g};\n"
        f"the most: {worst['value']} ({where}), {worst['p_zero']:+.3f} → {worst['p_uniform']:+.3f}",
        fontsize=8,
    )
    legend_right(ax, fontsize=7)
    return ax


def unseen_rows_figure(comparison: pd.DataFrame) -> Figure:
    """Notebook 03's figure of the all-zero rows against uniform rows: :func:`plot_unseen_rows` of
    ``comparison`` (:func:`glu.studies.replication.fusion.unseen_rows_comparison`)."""
    fig, (ax,) = new_figure(1, width=5, height=4.5)
    plot_unseen_rows(ax, comparison)
    return fig


def plot_structure(ax: Axes, bn, reference=None, reference_name: str = "the original") -> Axes:
    """The learned DAG as a matrix: one row per node with parents (children), one column per affordance node.

    Grey cells are edges parent → child; with a reference model, an edge only in ours is a red square, one
    only in the reference a hollow red square. A key below the matrix says so.
    """
    aff = list(bn.schema.affordance_nodes)
    children = [n for n in bn.nodes if bn.parents[n] or (reference is not None and reference.parents[n])]
    mat = np.array([[p in bn.parents[c] for p in aff] for c in children], dtype=float)
    ax.imshow(mat, cmap="Greys", vmin=0, vmax=1.6, aspect="auto", interpolation="nearest")
    ax.set_xticks(np.arange(len(aff) + 1) - 0.5, minor=True)
    ax.set_yticks(np.arange(len(children) + 1) - 0.5, minor=True)
    ax.grid(which="minor", color="0.85", linewidth=0.5)
    ax.tick_params(which="minor", length=0)
    only_ours = only_theirs = 0
    if reference is not None:
        for i, c in enumerate(children):
            for j, p in enumerate(aff):
                ours, theirs = p in bn.parents[c], p in reference.parents[c]
                if ours and not theirs:
                    ax.scatter(j, i, marker="s", color="red", s=30)
                    only_ours += 1
                elif theirs and not ours:
                    ax.scatter(j, i, marker="s", facecolors="none", edgecolors="red", s=30)
                    only_theirs += 1
    ax.set_xticks(range(len(aff)), aff, rotation=45, ha="left", fontsize=7)
    ax.xaxis.tick_top()
    ax.xaxis.set_label_position("top")
    ax.set_xlabel("parent (affordance node)", fontsize=8)
    ax.set_yticks(range(len(children)), children, fontsize=6)
    ax.set_ylabel("child (affordance node or word)", fontsize=8)
    n = len(bn.edges())
    title = f"{n} edges"
    if reference is not None:
        title += f"; {reference_name}: {len(reference.edges())}"
        title += f", {only_ours} only in ours, {only_theirs} only in theirs"
    ax.set_title(title, fontsize=9)
    handles = [Patch(facecolor=(0.45, 0.45, 0.45), label="edge parent → child")]
    if reference is not None:
        handles += [
            Line2D([], [], marker="s", color="red", ls="none", label="edge only in ours"),
            Line2D(
                [], [], marker="s", mfc="none", mec="red", ls="none", label=f"edge only in {reference_name}"
            ),
        ]
    ax.legend(
        handles=handles, fontsize=7, frameon=False, loc="upper center", bbox_to_anchor=(0.5, -0.01), ncols=1
    )
    return ax


def structure_figure(bn, reference=None) -> Figure:
    """Notebook 03's figure of the learned structure: :func:`plot_structure` of ``bn`` against ``reference``
    (None: none), tall enough for a row per word."""
    fig, (ax,) = new_figure(1, width=4.5, height=8)
    plot_structure(ax, bn, reference)
    return fig
