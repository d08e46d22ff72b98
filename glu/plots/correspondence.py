"""Figures of the correspondence study: accuracy across viewpoints and conditions, what each invariance
buys or costs, the spread of leave-one-out accuracy on the real data, one gesture seen from two sides.

Every function draws the tidy frames of :mod:`glu.experiments.correspondence` on the axes it is given and
returns them: ``plot_x(ax, frame, …) -> Axes``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from glu.plots.style import ACTION_COLORS

FEATURE_COLORS = {
    "raw": "0.2",
    "centred": "#4C72B0",
    "centred+scaled": "#55A868",
    "centred+rotated": "#C44E52",
    "centred+mirrored": "#8172B3",
    "centred+scaled+rotated+mirrored": "#DD8452",
    "body": "#937860",
    "body+centred": "#DA8BC3",
}
"""Colour of each default feature set (others get grey)."""


def _color(features: str) -> str:
    return FEATURE_COLORS.get(features, "0.55")


def plot_accuracy_vs_viewpoint(ax: Axes, summary: pd.DataFrame, train: str, chance: float = 1 / 3) -> Axes:
    """Accuracy (mean over seeds, shaded 95 % interval) against the person's turn, one line per feature set.

    ``summary`` as :func:`glu.experiments.correspondence.summarise` returns it; ``train`` picks the
    recognisers (``"robot"`` or ``"human"``).
    """
    s = summary[(summary["train"] == train) & (summary["factor"] == "viewpoint")]
    for features, g in s.groupby("features", sort=False):
        g = g.sort_values("yaw_deg")
        c = _color(features)
        ax.plot(g["yaw_deg"], g["accuracy"], "o-", color=c, lw=1.4, ms=3.5, label=features)
        if g["ci_low"].notna().any():
            ax.fill_between(g["yaw_deg"], g["ci_low"], g["ci_high"], color=c, alpha=0.12, lw=0)
    ax.axhline(chance, color="0.6", lw=0.8, ls=":", label="chance")
    ax.set_xlabel("person's turn relative to the camera (yaw, °)")
    ax.set_ylabel("accuracy")
    ax.set_xticks(sorted(s["yaw_deg"].dropna().unique()))
    ax.set_ylim(0, 1.02)
    ax.set_title(f"trained on {'the robot' if train == 'robot' else 'one human view'}", fontsize=9)
    return ax


def plot_accuracy_by_condition(
    ax: Axes, summary: pd.DataFrame, train: str, reference: tuple[str, str] = ("viewpoint", "0°")
) -> Axes:
    """Grouped bars: accuracy per condition other than the viewpoint sweep (and the reference), per feature
    set, with the 95 % interval as error bars."""
    s = summary[(summary["train"] == train)]
    s = s[(s["factor"] != "viewpoint") | ((s["factor"] == reference[0]) & (s["level"] == reference[1]))]
    conditions = list(dict.fromkeys(zip(s["factor"], s["level"], strict=True)))
    features = list(dict.fromkeys(s["features"]))
    w = 0.8 / len(features)
    for k, f in enumerate(features):
        g = s[s["features"] == f].set_index(["factor", "level"]).reindex(conditions)
        x = np.arange(len(conditions)) + (k - (len(features) - 1) / 2) * w
        err = np.vstack([g["accuracy"] - g["ci_low"], g["ci_high"] - g["accuracy"]])
        ax.bar(
            x,
            g["accuracy"],
            width=w,
            color=_color(f),
            label=f,
            yerr=None if np.isnan(err).all() else err,
            error_kw={"lw": 0.7, "capsize": 1.5},
        )
    labels = [
        "reference\n(standing, 0°)" if c == reference else c[1].replace(", ", ",\n") for c in conditions
    ]
    ax.set_xticks(np.arange(len(conditions)), labels, fontsize=7)
    ax.set_ylabel("accuracy")
    ax.set_ylim(0, 1.05)
    return ax


def plot_invariance_effects(ax: Axes, effects: pd.DataFrame, train: str) -> Axes:
    """A map of what adding each invariance changes (mean paired Δ accuracy; red: it costs, blue: it helps).

    Rows: feature set vs its baseline; columns: conditions. Cells whose 95 % interval excludes 0 are
    marked with the value in bold.
    """
    e = effects[effects["train"] == train].copy()
    e["row"] = e["features"] + "  vs  " + e["baseline"]
    e["col"] = e["factor"] + ": " + e["level"]
    rows, cols = list(dict.fromkeys(e["row"])), list(dict.fromkeys(e["col"]))
    m = e.pivot(index="row", columns="col", values="delta").reindex(index=rows, columns=cols)
    sure = (e["costs"] | e["helps"]).to_numpy()
    sure = pd.Series(sure, index=pd.MultiIndex.from_arrays([e["row"], e["col"]]))
    ax.imshow(m.to_numpy(dtype=float), cmap="RdBu", vmin=-1, vmax=1, aspect="auto")
    for i, r in enumerate(rows):
        for j, c in enumerate(cols):
            v = m.loc[r, c]
            if v == v:
                bold = bool(sure.get((r, c), False))
                ax.text(
                    j,
                    i,
                    f"{v:+.2f}",
                    ha="center",
                    va="center",
                    fontsize=6.5,
                    fontweight="bold" if bold else "normal",
                    color="black",
                )
    ax.set_xticks(range(len(cols)), cols, rotation=35, ha="right", fontsize=7)
    ax.set_yticks(range(len(rows)), rows, fontsize=7)
    ax.set_title(
        f"Δ accuracy when an invariance is added (trained on {train}; bold: 95 % interval excludes 0)",
        fontsize=8,
    )
    return ax


def plot_feature_settings(ax: Axes, grid: pd.DataFrame) -> Axes:
    """Leave-one-segment-out accuracy on the real segments, one point per (setting, seed), per feature set;
    filled points: the models trained on every segment also recognised every test gesture (the seated taps).

    ``grid`` as :func:`glu.experiments.seated.feature_settings` returns it.
    """
    features = list(dict.fromkeys(grid["features"]))
    settings = list(dict.fromkeys(grid["setting"]))
    n_test = int(grid.attrs.get("parameters", {}).get("n_test", 0))
    markers = "osD^v<>"
    for i, f in enumerate(features):
        g = grid[grid["features"] == f]
        for j, st in enumerate(settings):
            h = g[g["setting"] == st]
            x = i + (j - (len(settings) - 1) / 2) * 0.15 + np.linspace(-0.03, 0.03, len(h))
            for xi, (_, r) in zip(x, h.iterrows(), strict=True):
                full = n_test > 0 and r["test_correct"] == n_test
                ax.plot(
                    xi,
                    r["loso_accuracy"],
                    markers[j % len(markers)],
                    color=_color(f),
                    ms=5,
                    mfc=_color(f) if full else "none",
                )
        ax.hlines(g["loso_accuracy"].mean(), i - 0.4, i + 0.4, color=_color(f), lw=2)
    for j, st in enumerate(settings):
        ax.plot([], [], markers[j % len(markers)], color="0.3", mfc="none", label=st)
    ax.set_xticks(range(len(features)), features, fontsize=8)
    ax.set_ylabel("leave-one-segment-out accuracy")
    ax.set_ylim(0, 1.05)
    ax.legend(fontsize=7, frameon=False, title="setting (filled: seated taps all tap)", title_fontsize=7)
    return ax


def plot_nested_cv(ax: Axes, summary: pd.DataFrame) -> Axes:
    """The real data's nested cross-validation: per seed, the outer accuracy with its exact (Clopper–Pearson)
    interval; beside it, what tuning and reporting on the same segments gives, and the always-tap baseline.

    ``summary`` as :attr:`glu.experiments.nested.NestedCV.summary`.
    """
    x = np.arange(len(summary))
    ax.errorbar(
        x,
        summary["accuracy"],
        yerr=[summary["accuracy"] - summary["ci_low"], summary["ci_high"] - summary["accuracy"]],
        fmt="o",
        color="#4C72B0",
        capsize=3,
        label="nested (exact 95 % interval)",
    )
    ax.plot(
        x, summary["tuned_accuracy"], "_", color="#C44E52", ms=14, mew=2, label="tuned on the same segments"
    )
    ax.plot(x, summary["always_tap"], "_", color="0.5", ms=14, mew=2, label='always "tap"')
    ax.set_xticks(x, [f"seed {s}" for s in summary["seed"]], fontsize=8)
    ax.set_xlim(-0.6, len(summary) - 0.4)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("leave-one-segment-out accuracy")
    ax.set_title("real standing segments", fontsize=9)
    ax.legend(fontsize=7, frameon=False, loc="lower left")
    return ax


def plot_two_views(axes: Sequence[Axes], curves: pd.DataFrame, action: str) -> Sequence[Axes]:
    """``p_HMM(action | G_1^t)`` over time for each view (one axis each), raw (dashed) and aligned (solid).

    ``curves``: the concatenated :meth:`glu.experiments.two_views.ViewRun.curves` of the views.
    """
    for ax, (view, g) in zip(axes, curves.groupby("view", sort=False), strict=False):
        for name, ls in (("raw", "--"), ("aligned", "-")):
            h = g[(g["recogniser"] == name) & (g["action"] == action)]
            ax.plot(
                h["seconds"], h["p_hmm"], ls, color=ACTION_COLORS.get(action, "0.3"), label=f"{name} features"
            )
        ax.set_title(view, fontsize=9)
        ax.set_xlabel("time (s)")
        ax.set_ylim(-0.02, 1.02)
    axes[0].set_ylabel(f"p_HMM({action} | G_1^t)")
    axes[0].legend(fontsize=7, frameon=False)
    return axes
