"""Figures of the Affordance–Words network and of fusion: the papers' bar charts, sweeps and anticipation.

Every function draws on the axes it is given, first argument (a sequence of axes for multi-panel
figures), and returns them: ``plot_x(ax, frame, …)``. Frames are the tidy outputs of
:mod:`glu.experiments`; where they hold the original model's values (``p_original``), those are drawn as
black marks on our bars.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from glu.plots.style import ACTION_COLORS, ORIGINAL_MARK, VALUE_COLORS, bars_with_original


def plot_effect_prediction(axes: Sequence[Axes], df: pd.DataFrame) -> Sequence[Axes]:
    """GLU 2017 Fig. 4: bars of p(ObjVel | Action=tap, Shape, Size), one axis per case."""
    for ax, (case, g) in zip(axes, df.groupby("case", sort=False), strict=False):
        x = np.arange(len(g))
        orig = g["p_original"].to_numpy() if "p_original" in g else None
        bars_with_original(ax, x, g["p"].to_numpy(), [VALUE_COLORS.get(v, "0.6") for v in g["ObjVel"]], orig)
        ax.set_xticks(x, g["ObjVel"])
        ax.set_ylim(0, 1)
        ax.set_xlabel("ObjVel")
        ax.set_ylabel("probability")
        ax.set_title(f"tap on a {case}", fontsize=10)
        if orig is not None:
            ax.legend(fontsize=7, loc="upper left", frameon=False)
    return axes


def plot_word_change(ax: Axes, df: pd.DataFrame) -> Axes:
    """GLU 2017 Fig. 5: Δp(w) for the words whose probability changes by more than the threshold."""
    g = df[df["shown"]]
    x = np.arange(len(g))
    colors = np.where(g["delta"] > 0, "#DD8452", "#4C72B0")
    ax.bar(x, g["delta"], color=colors, edgecolor="0.2", linewidth=0.6)
    if "delta_original" in g:
        ax.plot(x, g["delta_original"], **ORIGINAL_MARK, label="original model")
        ax.legend(fontsize=7, frameon=False)
    ax.axhline(0, color="0.2", linewidth=0.8)
    ax.set_xticks(x, g["word"], rotation=60, ha="right")
    ax.set_ylabel(r"$\Delta p(w)$")
    ev = df.attrs.get("parameters", {}).get("evidence") or {}
    given = ", ".join(f"{k}={v}" for k, v in ev.items()) or "no evidence"
    ax.set_title(
        r"$p(w \mid F, E, A{=}tap) - p(w \mid F, E)$"
        + f"\nF, E = {given}"
        + (" (as the original code)" if "Color" in ev else " (as the paper's text)"),
        fontsize=9,
    )
    return ax


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
            ax.plot(x, g["p_original"], **{**ORIGINAL_MARK, "markersize": 6})
    ax.set_xticks(
        np.arange(len(cases)),
        [c.replace("no action evidence", "none") for c in cases],
        rotation=30,
        ha="right",
        fontsize=8,
    )
    ax.set_xlabel(r"$p_{HMM}$ [grasp tap touch]")
    ax.set_ylabel(r"$p_{comb}(Action)$")
    ax.set_ylim(0, 1)
    title = "action given soft evidence"
    if threshold is not None and np.isfinite(threshold):
        title += f" (tap wins for $p_{{HMM}}(tap) > {threshold:.4f}$)"
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8, frameon=False, ncols=len(actions))
    return ax


def plot_effect_vs_soft_evidence(
    axes: Sequence[Axes], df: pd.DataFrame, rule: str = "virtual"
) -> Sequence[Axes]:
    """TCDS: p_comb(ObjVel | Shape) stacked per p_hmm row, one axis per shape."""
    d = df[df["rule"] == rule]
    for ax, (shape, g) in zip(axes, d.groupby("Shape", sort=False), strict=False):
        cases = list(dict.fromkeys(g["case"]))
        bottom = np.zeros(len(cases))
        bottom_original = np.zeros(len(cases))
        for v in dict.fromkeys(g["ObjVel"]):
            rows = g[g["ObjVel"] == v].set_index("case").loc[cases]
            p = rows["p"].to_numpy()
            ax.bar(
                np.arange(len(cases)),
                p,
                bottom=bottom,
                color=VALUE_COLORS.get(v, "0.6"),
                label=v,
                edgecolor="0.2",
                linewidth=0.5,
            )
            bottom += p
            if "p_original" in rows:  # the original model's stack: a mark at the top of each value's bar
                bottom_original += rows["p_original"].to_numpy()
                ax.plot(
                    np.arange(len(cases)),
                    bottom_original,
                    **ORIGINAL_MARK,
                    label="original model" if v == g["ObjVel"].iloc[0] else None,
                )
        ax.set_xticks(
            np.arange(len(cases)),
            [c.replace("no action evidence", "none") for c in cases],
            rotation=30,
            ha="right",
            fontsize=8,
        )
        ax.set_ylim(0, 1)
        ax.set_ylabel(r"$p_{comb}(ObjVel)$")
        ax.set_xlabel(r"$p_{HMM}$ [grasp tap touch]")
        ax.set_title(f"{shape} ({rule} evidence)", fontsize=10)
    axes[-1].legend(
        fontsize=8,
        frameon=False,
        title="ObjVel",
        title_fontsize=8,
        loc="center left",
        bbox_to_anchor=(1.0, 0.5),
    )
    return axes


def plot_unseen_rows(ax: Axes, df: pd.DataFrame) -> Axes:
    """The original's all-zero rows vs uniform rows: the same numbers under both models."""
    for name, g in df.groupby("experiment", sort=False):
        ax.scatter(g["p_zero"], g["p_uniform"], s=14, label=name, alpha=0.8)
    lo = min(df["p_zero"].min(), df["p_uniform"].min())
    ax.plot([lo, 1], [lo, 1], color="0.5", linewidth=0.8)
    ax.set_xlabel("original: all-zero rows (faithful)")
    ax.set_ylabel("corrected: uniform rows")
    worst = df.loc[df["uniform_minus_zero"].abs().idxmax()]
    ax.set_title(
        f"largest change {worst['uniform_minus_zero']:+.3f} ({worst['experiment']}, {worst['value']})",
        fontsize=8,
    )
    ax.legend(fontsize=7, frameon=False)
    return ax


def plot_structure(ax: Axes, bn, reference=None) -> Axes:
    """The learned DAG as a matrix: one row per node with parents, one column per affordance node.

    Filled cells are edges; with a reference model, edges only in ours are red, only in the reference are
    hollow squares.
    """
    aff = list(bn.schema.affordance_nodes)
    children = [n for n in bn.nodes if bn.parents[n] or (reference is not None and reference.parents[n])]
    mat = np.array([[p in bn.parents[c] for p in aff] for c in children], dtype=float)
    ax.imshow(mat, cmap="Greys", vmin=0, vmax=1.6, aspect="auto", interpolation="nearest")
    if reference is not None:
        for i, c in enumerate(children):
            for j, p in enumerate(aff):
                ours, theirs = p in bn.parents[c], p in reference.parents[c]
                if ours and not theirs:
                    ax.scatter(j, i, marker="s", color="red", s=30)
                elif theirs and not ours:
                    ax.scatter(j, i, marker="s", facecolors="none", edgecolors="red", s=30)
    ax.set_xticks(range(len(aff)), aff, rotation=45, ha="left", fontsize=7)
    ax.xaxis.tick_top()
    ax.set_yticks(range(len(children)), children, fontsize=6)
    ax.set_title(
        f"{len(bn.edges())} edges" + ("" if reference is None else f" (original: {len(reference.edges())})"),
        fontsize=9,
        pad=30,
    )
    return ax


def plot_soft_sweep(ax: Axes, df: pd.DataFrame) -> Axes:
    """p_comb(target) against p_hmm(tap): one colour per value, solid for virtual, dashed for Jeffrey."""
    target = [c for c in df.columns if c not in ("evidence", "rule", "p_hmm_tap", "p")][0]
    styles = {"virtual": "-", "jeffrey": "--", "hard": ":", "product": "-"}
    for (rule, value), g in df.groupby(["rule", target], sort=False):
        ax.plot(
            g["p_hmm_tap"],
            g["p"],
            styles.get(rule, "-"),
            color=VALUE_COLORS.get(value, ACTION_COLORS.get(value, "0.4")),
            label=f"{value} ({rule})",
        )
    ax.set_xlabel(r"$p_{HMM}(tap)$ (rest split equally)")
    ax.set_ylabel(rf"$p_{{comb}}({target})$")
    ax.set_ylim(0, 1)
    ax.set_xlim(0, 1)
    ax.set_title(df["evidence"].iloc[0], fontsize=9)
    ax.legend(fontsize=7, frameon=False, ncols=2)
    return ax


def plot_tap_thresholds(ax: Axes, df: pd.DataFrame) -> Axes:
    """The p_hmm(tap) above which tap wins, for each (Shape, Size, ObjVel)."""
    labels = [", ".join(str(r[c]) for c in df.columns[:-2]) for _, r in df.iterrows()]
    y = np.arange(len(df))
    ax.barh(y, df["threshold"].fillna(0), color=ACTION_COLORS["tap"], edgecolor="0.2", linewidth=0.5)
    for yi, t in zip(y, df["threshold"], strict=True):
        text = "never (tap cannot win)" if np.isnan(t) else "any > 0" if t < 0.005 else f"{t:.3f}"
        ax.text(
            0.01 if np.isnan(t) or t < 0.005 else t + 0.01, yi, text, va="center", fontsize=6.5, color="0.25"
        )
    ax.axvline(1 / 3, color="0.4", linestyle=":", linewidth=1, label="uniform (1/3)")
    ax.legend(fontsize=7, frameon=False, loc="lower right")
    ax.set_yticks(y, labels, fontsize=7)
    ax.invert_yaxis()
    ax.set_xlim(0, 1)
    ax.set_xlabel(r"$p_{HMM}(tap)$ needed for tap to win")
    return ax


def plot_anticipation(
    axes: Sequence[Axes], curves: pd.DataFrame, predictions: pd.DataFrame, node: str = "ObjVel"
) -> Sequence[Axes]:
    """TCDS effect anticipation: (1/t) log L per model (top) and p_comb(node) every few frames (bottom)."""
    top, bottom = axes
    for action, g in curves.groupby("action", sort=False):
        top.plot(g["frame"], g["loglik_per_frame"], color=ACTION_COLORS.get(action, "0.4"), label=action)
    top.set_ylabel(r"$\frac{1}{t}\log L(G_1^t \mid A)$")
    top.legend(fontsize=8, frameon=False)
    title = f"{curves['case'].iloc[0]} — HMMs: {curves['models'].iloc[0]}"
    top.set_title(title, fontsize=9)
    d = predictions[predictions["node"] == node]
    frames = np.array(sorted(d["frame"].unique()))
    width = 0.8 * (float(np.median(np.diff(frames))) if len(frames) > 1 else 1.0)
    bottom_acc = np.zeros(len(frames))
    for v in dict.fromkeys(d["value"]):
        p = d[d["value"] == v].set_index("frame").loc[frames, "p"].to_numpy()
        bottom.bar(
            frames,
            p,
            width=width,
            bottom=bottom_acc,
            color=VALUE_COLORS.get(v, ACTION_COLORS.get(v, "0.6")),
            label=v,
            edgecolor="0.2",
            linewidth=0.3,
        )
        bottom_acc += p
    bottom.set_ylim(0, 1)
    bottom.set_ylabel(rf"$p_{{comb}}({node})$")
    bottom.set_xlabel("frame")
    bottom.legend(fontsize=7, frameon=False, loc="center left", bbox_to_anchor=(1.0, 0.5))
    return axes


def plot_fusion_on_gestures(ax: Axes, df: pd.DataFrame, value: str = "fast", target: str = "ObjVel") -> Axes:
    """p_comb(target = value) per gesture segment, one bar per fusion strategy; HMM's top action below."""
    d = df[df[target] == value]
    segs = list(dict.fromkeys(zip(d["recording"], d["start"], d["end"], strict=True)))
    strategies = list(dict.fromkeys(d["strategy"]))
    w = 0.8 / len(strategies)
    hatches = {"hard": "", "virtual": "//", "jeffrey": ".."}
    for k, st in enumerate(strategies):
        g = d[d["strategy"] == st].set_index(["recording", "start", "end"]).loc[segs]
        ax.bar(
            np.arange(len(segs)) + (k - (len(strategies) - 1) / 2) * w,
            g["p"],
            width=w,
            color="#66C2A5",
            hatch=hatches.get(st, ""),
            edgecolor="0.2",
            linewidth=0.5,
            label=st,
        )
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
        fontsize=6.5,
    )
    ax.set_ylim(0, 1)
    ax.set_ylabel(rf"$p_{{comb}}({target}={value})$")
    ax.set_title(d["evidence"].iloc[0], fontsize=9)
    ax.legend(fontsize=8, frameon=False)
    return ax
