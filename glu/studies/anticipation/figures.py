"""The effect-anticipation figure (TCDS 2020 Fig. 5): per-frame log-likelihoods and p_comb(ObjVel) over time.

One column per case (a tap on a small sphere, a tap on a big box). Top: ``(1/t) log L(G_1^t | A)`` of each
action's HMM, frame by frame, with the time in seconds on the top axis. Bottom: ``p_comb(ObjVel)`` at each
update, and above it, in words, which action the HMMs put ahead and what that predicts. With the published
values (:func:`glu.studies.anticipation.experiment.published_comparison`) the figure draws the paper's curves
under glu's — wide pale lines under thin ones — and the paper's final bars beside glu's last update, so the
match can be seen. :func:`anticipation_figure` builds the whole figure; :func:`plot_anticipation` draws one
case on the axes it is given; :func:`shared_ylim` gives several figures the same y axis;
:func:`bank_figures` builds one figure per bank of HMMs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

from glu.plots.style import ACTION_COLORS, VALUE_COLORS, balanced_fill
from glu.studies.anticipation.experiment import CASES, AnticipationRun

PUBLISHED_LABEL = "TCDS 2020 Fig. 5 (read from the authors' EPS)"
LOGLIK_LABEL = r"$(1/t)\,\log L(G_1^t \mid A)$"
SYMLOG_THRESHOLD = 10.0
"""With a shared y axis over a wide range: linear within ±this, logarithmic beyond."""
SYMLOG_TICKS = (10, 5, 0, -5, -10, -30, -100, -300, -1000)


def _color(v: str) -> str:
    return VALUE_COLORS.get(v, ACTION_COLORS.get(v, "0.6"))


def plot_anticipation(
    axes: Sequence[Axes],
    curves: pd.DataFrame,
    predictions: pd.DataFrame,
    node: str = "ObjVel",
    published: pd.DataFrame | None = None,
    ylim: tuple[float, float] | None = None,
) -> Sequence[Axes]:
    """One case: the per-frame log-likelihoods (``axes[0]``), p_comb(node) at each update (``axes[1]``).

    Parameters
    ----------
    axes : (curves axes, bars axes) or, with ``published``, (curves, bars, final bars)
    curves : :meth:`AnticipationRun.curves` (columns frame, t, seconds, action, loglik_per_frame, p_hmm)
    predictions : :meth:`AnticipationRun.predictions` (columns frame, t, node, value, p)
    published : :func:`glu.studies.anticipation.experiment.published_comparison` of the same run: its curves
        are drawn under glu's, its bars beside glu's last update in ``axes[2]``
    ylim : y range of the curves (a wide one is drawn linear within ±:data:`SYMLOG_THRESHOLD`, log beyond)
    """
    top, bottom = axes[0], axes[1]
    frame_of_t = dict(zip(curves["t"], curves["frame"], strict=False))
    for action, g in curves.groupby("action", sort=False):
        color = ACTION_COLORS.get(action, "0.4")
        top.plot(g["frame"], g["loglik_per_frame"], color=color, lw=1.3, label=action, zorder=3)
        if published is not None:
            p = published[(published["quantity"] == "loglik_per_frame") & (published["key"] == action)]
            top.plot(p["t"].map(frame_of_t), p["paper"], color=color, lw=6, alpha=0.3, solid_capstyle="butt")
    top.set_ylabel(LOGLIK_LABEL)
    if ylim is not None:
        if ylim[0] < -3 * SYMLOG_THRESHOLD:
            top.set_yscale("symlog", linthresh=SYMLOG_THRESHOLD, linscale=1.5)
            ticks = [v for v in SYMLOG_TICKS if ylim[0] <= v <= ylim[1]]
            top.yaxis.set_major_locator(FixedLocator(ticks))
            top.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}".replace("-", "−")))
            top.yaxis.set_minor_locator(NullLocator())
            top.set_ylabel(LOGLIK_LABEL + f"\n(linear within ±{SYMLOG_THRESHOLD:g}, log beyond)")
        top.set_ylim(*ylim)
    case = str(curves["case"].iloc[0])
    what = CASES[case].description if case in CASES else case
    title = f"{what} — HMMs: {curves['models'].iloc[0]}"
    if published is not None:
        c = published[published["quantity"] == "loglik_per_frame"]
        title += (
            f"\npaper's curves ({len(c)} points): max |glu − paper| = {c['difference'].abs().max():.1e}"
            f" (read to ±{c['resolution'].max():.0e})"
        )
    top.set_title(title, fontsize=9)
    _seconds_axis(top, curves)

    d = predictions[predictions["node"] == node]
    frames = np.array(sorted(d["frame"].unique()))
    width = 0.8 * (float(np.median(np.diff(frames))) if len(frames) > 1 else 1.0)
    stack = np.zeros(len(frames))
    for v in dict.fromkeys(d["value"]):
        p = d[d["value"] == v].set_index("frame").loc[frames, "p"].to_numpy()
        bottom.bar(frames, p, width=width, bottom=stack, color=_color(v), label=v, edgecolor="0.2", lw=0.3)
        stack += p
    bottom.set_ylim(0, 1)
    bottom.set_ylabel(rf"$p_{{comb}}({node})$")
    bottom.set_xlabel("frame of the recording (updates every 5 frames)")
    inches = bottom.get_position().width * bottom.figure.get_figwidth()
    chars = max(40, int(inches * 72 / (0.55 * 8)))  # about as wide as the panel, at 8 pt
    bottom.set_title(balanced_fill(prediction_summary(curves, predictions, node), chars), fontsize=8)
    if published is not None and len(axes) > 2:
        _final_bars(axes[2], d, published, node)
    return axes


def prediction_summary(curves: pd.DataFrame, predictions: pd.DataFrame, node: str = "ObjVel") -> str:
    """In words: which action the HMMs put ahead at the updates, and the most probable ``node`` value then.

    E.g. ``"t = 5–20: tap ahead → fast 0.52; t = 25: touch ahead → slow 0.91; …"``: consecutive
    updates with the same leading action (the largest p_HMM) and the same most probable value are one
    stretch.
    """
    d = predictions[predictions["node"] == node]
    lead = curves.loc[curves.groupby("t")["p_hmm"].idxmax(), ["t", "action"]].set_index("t")["action"]
    top = d.loc[d.groupby("t")["p"].idxmax(), ["t", "value", "p"]].sort_values("t")
    stretches: list[list] = []
    for t, value, p in top.itertuples(index=False):
        key = (lead.get(t, "?"), value)
        if stretches and stretches[-1][0] == key:
            stretches[-1][2] = t
            stretches[-1][3].append(p)
        else:
            stretches.append([key, t, t, [p]])
    parts = []
    for (action, value), t0, t1, ps in stretches:
        when = f"t\u00a0=\u00a0{t0}" if t0 == t1 else f"t\u00a0=\u00a0{t0}–{t1}"  # unbreakable
        lo, hi = f"{min(ps):.2f}", f"{max(ps):.2f}"
        p = hi if lo == hi else f"{lo}–{hi}"
        parts.append(f"{when}: {action} ahead → {value} {p}")
    return "; ".join(parts)


def _seconds_axis(ax: Axes, curves: pd.DataFrame) -> None:
    """Seconds since the gesture's first frame on the top axis (a linear map of the frame numbers)."""
    if "seconds" not in curves or curves["frame"].nunique() < 2:
        return
    g = curves.drop_duplicates("frame").sort_values("frame")
    f0, s0 = float(g["frame"].iloc[0]), float(g["seconds"].iloc[0])
    rate = float(np.median(np.diff(g["seconds"]) / np.diff(g["frame"])))  # seconds per frame
    sec = ax.secondary_xaxis(
        "top", functions=(lambda f: s0 + (f - f0) * rate, lambda s: f0 + (s - s0) / rate)
    )
    sec.set_xlabel("seconds since the gesture's first frame", fontsize=8)
    sec.tick_params(labelsize=8)


def _final_bars(ax: Axes, d: pd.DataFrame, published: pd.DataFrame, node: str) -> None:
    """glu's p_comb at the paper's last update beside the published bars, stacked, with their values."""
    bars = published[published["quantity"] == node]
    t = int(bars["t"].iloc[0])
    ours = d[d["t"] == t].set_index("value")["p"]
    paper = bars.set_index("key")["paper"]
    for x, values in ((0, ours), (1, paper)):
        stack = 0.0
        for v in bars["key"]:
            p = float(values[v])
            ax.bar(x, p, bottom=stack, width=0.7, color=_color(v), edgecolor="0.2", lw=0.3)
            if p >= 0.12:
                ax.text(x, stack + p / 2, f"{p:.3f}", ha="center", va="center", fontsize=7)
            stack += p
    ax.set_xticks([0, 1], [f"glu\nt = {t}", "paper"], fontsize=8)
    ax.set_xlim(-0.6, 1.6)
    ax.set_ylim(0, 1)
    ax.tick_params(labelleft=False)
    ax.set_title(f"last update\nmax |Δ| = {bars['difference'].abs().max():.0e}", fontsize=8)


def shared_ylim(curves: Sequence[pd.DataFrame], pad: float = 0.04) -> tuple[float, float]:
    """One y range holding every per-frame log-likelihood of ``curves``, for figures compared by eye."""
    values = np.concatenate([c["loglik_per_frame"].to_numpy(dtype=float) for c in curves])
    lo, hi = float(values.min()), float(values.max())
    return lo - pad * abs(lo), hi + pad * max(abs(hi), 1.0)


def anticipation_figure(
    cases: Sequence[tuple[pd.DataFrame, pd.DataFrame]],
    published: Sequence[pd.DataFrame | None] | None = None,
    ylim: tuple[float, float] | None = None,
    node: str = "ObjVel",
) -> Figure:
    """The whole figure: one column per ``(curves, predictions)`` case, one legend above.

    With ``published`` (one comparison frame per case, or None), a narrow column beside each case shows
    glu's last update and the paper's bars; the paper's curves are drawn under glu's.
    """
    with_paper = published is not None and any(p is not None for p in published)
    cols = [5.0, 1.15] if with_paper else [5.0]
    fig = plt.figure(figsize=(5.2 * len(cases) + (2.2 if with_paper else 0), 6.4), layout="constrained")
    grid = fig.add_gridspec(2, len(cols) * len(cases), width_ratios=cols * len(cases))
    for j, (curves, predictions) in enumerate(cases):
        k = j * len(cols)
        top = fig.add_subplot(grid[0, k])
        bottom = fig.add_subplot(grid[1, k], sharex=top)
        top.tick_params(labelbottom=False)
        axes = [top, bottom]
        paper = published[j] if with_paper else None
        if paper is not None:
            axes.append(fig.add_subplot(grid[1, k + 1], sharey=bottom))
        plot_anticipation(axes, curves, predictions, node, paper, ylim)
    values = list(dict.fromkeys(predictions[predictions["node"] == node]["value"]))
    handles = [
        Line2D([], [], color=ACTION_COLORS.get(a, "0.4"), lw=1.3, label=a)
        for a in dict.fromkeys(curves["action"])
    ]
    if with_paper:
        handles += [
            Line2D([], [], color="0.3", lw=1.3, label="glu"),
            Line2D([], [], color="0.3", lw=6, alpha=0.3, label=PUBLISHED_LABEL),
        ]
    handles += [Patch(facecolor=_color(v), edgecolor="0.2", lw=0.3, label=f"{node} {v}") for v in values]
    fig.legend(handles=handles, loc="outside upper center", ncols=len(handles), fontsize=8, frameon=False)
    return fig


def bank_figures(
    runs: Mapping[tuple[str, str], AnticipationRun],
    published: Mapping[str, pd.DataFrame],
    paper_bank: str = "original",
) -> dict[str, Figure]:
    """One :func:`anticipation_figure` per bank of HMMs of ``runs`` (by (case, bank), its cases in the order
    of :data:`~glu.studies.anticipation.experiment.CASES`), by bank: ``paper_bank``'s with the published
    Fig. 5 (``published``, by case) on its own y axis; the others on one y axis they share
    (:func:`shared_ylim`), to be compared by eye."""
    banks = list(dict.fromkeys(name for _, name in runs))
    others = [r.curves() for (_, name), r in runs.items() if name != paper_bank]
    ylim = shared_ylim(others) if others else None
    out = {}
    for name in banks:
        cases = [case for case in CASES if (case, name) in runs]
        drawn = [(runs[case, name].curves(), runs[case, name].predictions()) for case in cases]
        if name == paper_bank:
            out[name] = anticipation_figure(drawn, [published.get(case) for case in cases])
        else:
            out[name] = anticipation_figure(drawn, ylim=ylim)
    return out
