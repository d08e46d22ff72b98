"""Figures of the correspondence study: accuracy across viewpoints and conditions, what each invariance
buys or costs, the spread of leave-one-out accuracy on the real data, one gesture seen from two sides.

Every function draws the tidy frames of :mod:`glu.studies.correspondence.experiment` on the axes it is given
and returns them: ``plot_x(ax, frame, …) -> Axes``; the ``*_figure`` functions lay out notebook 10's figures
from them, one call each. Feature sets are named as in the text (``all`` for the four invariances together);
conditions by their factor and level (``body size 0.8``).
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from glu.gestures.invariants import ALL, INVARIANCES
from glu.plots.style import ACTION_COLORS, legend_right, new_figure
from glu.studies.correspondence.experiment import OCCLUDED, TRAIN_SOURCES

FEATURE_COLORS = {
    "raw": "0.2",
    "centred": "#4C72B0",
    "centred+scaled": "#55A868",
    "centred+rotated": "#C44E52",
    "centred+mirrored": "#8172B3",
    ALL: "#DD8452",
    "body": "#937860",
    "body+centred": "#DA8BC3",
}
"""Colour of each default feature set (others get grey)."""
FEATURE_MARKERS = {
    "raw": "o",
    "centred": "s",
    "centred+scaled": "^",
    "centred+rotated": "v",
    "centred+mirrored": "D",
    ALL: "P",
    "body": "X",
    "body+centred": "*",
}
FEATURE_LINES = {"raw": "-", "centred": "--", "centred+scaled": "-.", "centred+rotated": ":", "body": "-"}
FEATURE_HATCHES = {
    "centred": "//",
    "centred+scaled": "\\\\",
    "centred+rotated": "xx",
    "centred+mirrored": "..",
    ALL: "++",
    "body": "oo",
    "body+centred": "--",
}
"""Each feature set's marker, line style and hatching: seven series on one axis are told apart by more than
their hue (colour-blind readers, grey prints)."""
RECOGNISER_LABELS = {"raw": "raw features", "aligned": f"invariant features ({ALL})"}
"""How :func:`plot_two_views` names the two recognisers of :meth:`ViewRun.curves`."""


def feature_label(features: str) -> str:
    """A feature set as the text names it: ``all`` for the four invariances together."""
    return ALL if features == "+".join(INVARIANCES) else features


def _color(features: str) -> str:
    return FEATURE_COLORS.get(feature_label(features), "0.55")


def _marker(features: str) -> str:
    return FEATURE_MARKERS.get(feature_label(features), "o")


def _line(features: str) -> str:
    return FEATURE_LINES.get(feature_label(features), "-")


def trained_on(train: str) -> str:
    """The recognisers' training source in words: ``"the robot"``, ``"one human view"``."""
    return "the robot" if train == "robot" else "one human view"


def condition_label(factor: str, level: str, width: int = 14) -> str:
    """A condition as a short multi-line label: ``"body size\\n0.8"``, ``"sensor noise\\n3 cm"``."""
    if factor in ("combined", "performer"):
        return textwrap.fill(level if factor == "performer" else f"combined: {level}", width)
    if factor == "mirror":
        return level
    return f"{textwrap.fill(factor, width)}\n{level}"


def plot_accuracy_vs_viewpoint(
    ax: Axes,
    summary: pd.DataFrame,
    train: str,
    chance: float = 1 / 3,
    legend: bool = False,
    factor: str = "viewpoint",
) -> Axes:
    """Accuracy (mean over seeds, 95 % interval as an error bar) against the person's turn, per feature set
    (each its colour, marker and line style).

    ``summary`` as :func:`glu.studies.correspondence.experiment.summarise` returns it; ``train`` picks the
    recognisers (``"robot"`` or ``"human"``); ``factor`` the turns seen by the ideal tracker
    (``"viewpoint"``) or by the occluding one (:data:`~glu.studies.correspondence.experiment.OCCLUDED`, with
    the front view of the ideal tracker, which sees the same). The feature sets are set a few degrees apart
    so that their intervals can be told apart. ``legend``: a legend right of the axes.
    """
    s = summary[(summary["train"] == train)]
    front = s[(s["factor"] == "viewpoint") & (s["yaw_deg"] == 0)]
    s = pd.concat([front, s[s["factor"] == factor]]) if factor != "viewpoint" else s[s["factor"] == factor]
    groups = list(s.groupby("features", sort=False))
    yaws = sorted(s["yaw_deg"].dropna().unique())
    step = float(np.min(np.diff(yaws))) if len(yaws) > 1 else 30.0
    offset = 0.5 * step / max(len(groups), 1)
    for k, (features, g) in enumerate(groups):
        g = g.sort_values("yaw_deg")
        c = _color(features)
        x = g["yaw_deg"] + (k - (len(groups) - 1) / 2) * offset
        err = np.vstack([g["accuracy"] - g["ci_low"], g["ci_high"] - g["accuracy"]])
        ax.errorbar(
            x,
            g["accuracy"],
            yerr=None if np.isnan(err).all() else err,
            marker=_marker(features),
            ls=_line(features),
            color=c,
            lw=1.2,
            ms=4,
            elinewidth=0.8,
            capsize=0,
            label=feature_label(features),
        )
    ax.axhline(chance, color="0.6", lw=0.8, ls=":", label="chance")
    ax.set_xlabel("person's turn relative to the camera (yaw, °)")
    ax.set_ylabel("accuracy (mean over seeds, 95 % interval)")
    ax.set_xticks(yaws)
    ax.set_ylim(0, 1.02)
    tracker = "" if factor == "viewpoint" else ", occluding tracker"
    ax.set_title(f"trained on {trained_on(train)}{tracker}", fontsize=9)
    if legend:
        _features_legend(ax)
    return ax


def plot_accuracy_by_condition(
    ax: Axes,
    summary: pd.DataFrame,
    train: str,
    reference: tuple[str, str] = ("viewpoint", "0°"),
    legend: bool = True,
) -> Axes:
    """Grouped bars: accuracy per condition other than the viewpoint sweep (and the reference), per feature
    set, with the 95 % interval as error bars. ``legend``: a legend right of the axes."""
    s = summary[(summary["train"] == train) & ~summary["factor"].str.startswith("viewpoint,")]
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
            hatch=FEATURE_HATCHES.get(feature_label(f)),
            edgecolor="white",
            lw=0,
            label=feature_label(f),
            yerr=None if np.isnan(err).all() else err,
            error_kw={"lw": 0.7, "capsize": 1.5},
        )
    labels = ["reference\n(standing, 0°)" if c == reference else condition_label(*c) for c in conditions]
    ax.set_xticks(np.arange(len(conditions)), labels, fontsize=7.5)
    ax.set_ylabel("accuracy (95 % interval)")
    ax.set_ylim(0, 1.05)
    if legend:
        _features_legend(ax)
    return ax


def plot_invariance_effects(ax: Axes, effects: pd.DataFrame, train: str) -> Axes:
    """A map of what adding each invariance changes (mean paired Δ accuracy; red: it costs, blue: it helps).

    Rows: feature set vs its baseline; columns: conditions. Cells whose adjusted verdict is a difference
    (Benjamini–Hochberg over the table) are marked with the value in bold.
    """
    e = effects[effects["train"] == train].copy()
    e["row"] = e["features"].map(feature_label) + "  vs  " + e["baseline"].map(feature_label)
    e["col"] = e["factor"] + "\t" + e["level"]
    cols = list(dict.fromkeys(e["col"]))
    rows = list(dict.fromkeys(e["row"]))
    m = e.pivot(index="row", columns="col", values="delta").reindex(index=rows, columns=cols)
    sure = (e["costs"] | e["helps"]).to_numpy()
    sure = pd.Series(sure, index=pd.MultiIndex.from_arrays([e["row"], e["col"]]))
    ax.imshow(m.to_numpy(dtype=float), cmap="RdBu", vmin=-1, vmax=1, aspect="auto")
    for i, r in enumerate(rows):
        for j, c in enumerate(cols):
            v = m.loc[r, c]
            if v == v:
                bold = bool(sure.get((r, c), False))
                weight = "bold" if bold else "normal"
                ax.text(j, i, f"{v:+.2f}", ha="center", va="center", fontsize=7, fontweight=weight)
    ax.set_xticks(range(len(cols)), [condition_label(*c.split("\t"), width=10) for c in cols], fontsize=7)
    ax.set_yticks(range(len(rows)), rows, fontsize=7.5)
    ax.set_title(
        f"Δ accuracy when an invariance is added (trained on {train}; bold: a difference after the "
        "multiplicity adjustment)",
        fontsize=8.5,
    )
    return ax


def plot_nested_cv(ax: Axes, summary: pd.DataFrame) -> Axes:
    """The real data's nested cross-validation: per seed, the outer accuracy with its exact (Clopper–Pearson)
    interval; beside it, what tuning and reporting on the same segments gives, and the always-tap baseline.

    ``summary`` as :attr:`glu.studies.correspondence.nested.NestedCV.summary`.
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
    """``p_HMM(action | G_1^t)`` over time for each view (one axis each), raw (dashed) and invariant (solid).

    ``curves``: the concatenated :meth:`glu.studies.correspondence.two_views.ViewRun.curves` of the views.
    """
    for ax, (view, g) in zip(axes, curves.groupby("view", sort=False), strict=False):
        for name, ls in (("raw", "--"), ("aligned", "-")):
            h = g[(g["recogniser"] == name) & (g["action"] == action)]
            ax.plot(
                h["seconds"],
                h["p_hmm"],
                ls,
                color=ACTION_COLORS.get(action, "0.3"),
                label=RECOGNISER_LABELS[name],
            )
        ax.set_title(view, fontsize=9)
        ax.set_xlabel("time (s)")
        ax.set_ylim(-0.02, 1.02)
    axes[0].set_ylabel(rf"$p_{{HMM}}({action} \mid G_1^t)$")
    legend_right(axes[-1])
    return axes


VIEWPOINT_PANELS: tuple[tuple[str, str], ...] = (
    ("robot", "viewpoint"),
    ("human", "viewpoint"),
    ("human", OCCLUDED),
)
"""The panels of :func:`viewpoint_figure`: (training source, factor of the turns)."""


def viewpoint_figure(summary: pd.DataFrame) -> Figure:
    """Accuracy against the person's turn (:func:`plot_accuracy_vs_viewpoint`), one panel per
    :data:`VIEWPOINT_PANELS` whose turns the summary holds: trained on the robot, on one human view, and on
    one human view with the turns seen by the occluding tracker; the legend right of the last."""
    panels = [(t, f) for t, f in VIEWPOINT_PANELS if f in set(summary["factor"])]
    fig, axes = new_figure(len(panels), width=4.6, height=3.6)
    for ax, (train, factor) in zip(axes, panels, strict=True):
        plot_accuracy_vs_viewpoint(ax, summary, train, legend=ax is axes[-1], factor=factor)
    return fig


def conditions_figure(summary: pd.DataFrame, train: str = "human") -> Figure:
    """Accuracy in every test condition of one training source, a bar per feature set
    (:func:`plot_accuracy_by_condition`), titled by the source."""
    fig, (ax,) = new_figure(1, width=11, height=3.4)
    plot_accuracy_by_condition(ax, summary, train)
    ax.set_title(f"trained on {trained_on(train)}", fontsize=9)
    return fig


def invariance_effects_figure(effects: pd.DataFrame, trains: Sequence[str] = TRAIN_SOURCES) -> Figure:
    """What adding each invariance changes (:func:`plot_invariance_effects`), one map per training source,
    stacked."""
    fig, axes = new_figure(1, width=13, height=3.5, nrows=len(trains))
    for ax, train in zip(axes, trains, strict=True):
        plot_invariance_effects(ax, effects, train)
    return fig


def nested_cv_figure(summary: pd.DataFrame) -> Figure:
    """The real data's nested cross-validation, per seed (:func:`plot_nested_cv`)."""
    fig, (ax,) = new_figure(1, width=5, height=3.4)
    plot_nested_cv(ax, summary)
    return fig


def two_views_figure(curves: pd.DataFrame, action: str = "tap") -> Figure:
    """``p_HMM(action | G_1^t)`` over time, one panel per view of ``curves`` (:func:`plot_two_views`)."""
    fig, axes = new_figure(curves["view"].nunique(), width=4.2, height=2.8)
    plot_two_views(axes, curves, action)
    return fig


def _features_legend(ax: Axes) -> None:
    """The legend of the feature sets, right of the axes."""
    legend_right(ax, title="features", title_fontsize=8)
