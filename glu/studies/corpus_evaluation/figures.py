"""Figures of the corpus evaluation: which fusion strategy wins where, with 95 % intervals.

The ``plot_*`` functions draw the sweep's tables (:mod:`glu.studies.corpus_evaluation.tables`:
``results``, ``differences``, ``reliability``) on the axes they are given and return them. In those tables a
noise of NaN means "pooled over the noise levels" and a viewpoint ``"all"`` "pooled over the viewpoints";
``where`` picks one cell of the design (action prior, inference network, learn_experiments, p_HMM reading;
default :data:`glu.studies.corpus_evaluation.findings.REFERENCE_CELL`), which the panel's title names.
Strategies whose lines coincide are named in the panel's title, so that a line hidden under another is not
missed.

The ``*_figure`` functions lay out whole figures from those panels (constrained layout; one legend above the
panels, naming every strategy drawn once), one column per cell of the design given (``cells``: e.g. the
reference cell and the most mismatched one, :func:`glu.studies.corpus_evaluation.findings.contrast_cells`), to
fit a page.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from glu.plots.style import (
    STRATEGY_COLORS,
    STRATEGY_MARKERS,
    balanced_fill,
    strategy_label,
    strategy_style,
)
from glu.studies.corpus_evaluation.findings import (
    CELL,
    REFERENCE_CELL,
    cell_label,
    metric_rows,
    pair,
    select,
    viewpoints,
)

METRIC_LABEL = {
    "accuracy": "accuracy",
    "log_loss": "log-loss (nats)",
    "brier": "Brier score",
    "ece": "ECE (bias-corrected)",
}
COINCIDE = 0.01
"""Lines closer than this fraction of the axis' range at every point coincide (and the title says so)."""
MARKER_SIZE = 4.5
"""Points: the strategies' markers on lines, large enough that their shapes tell them apart."""
LINE_WIDTH = 1.3
"""Points: a strategy's line."""
TITLE_CHARS = 52
"""A panel's title is wrapped at this many characters, so that titles of panels side by side keep apart."""


def where_label(where: Mapping[str, Any] | None) -> str:
    """A cell of the design in words (:func:`glu.studies.corpus_evaluation.findings.cell_label`; None: the
    reference cell)."""
    return cell_label({**REFERENCE_CELL, **(where or {})})


def _cell(frame: pd.DataFrame, where: Mapping[str, Any] | None) -> pd.DataFrame:
    """The rows of one cell of the design (``where``: column → value; None: the reference cell)."""
    return select(frame, REFERENCE_CELL if where is None else where)


def _pooled(
    frame: pd.DataFrame, noise: float | None, viewpoint: str, where: Mapping[str, Any] | None
) -> pd.DataFrame:
    frame = _cell(frame, where)
    sel = frame.viewpoint == viewpoint
    return frame[sel & (frame.noise.isna() if noise is None else np.isclose(frame.noise, noise))]


def _line(ax: Axes, x: np.ndarray, g: pd.DataFrame, strategy: str) -> Line2D:
    style = strategy_style(strategy)
    ax.fill_between(x, g.ci_low, g.ci_high, color=style["color"], alpha=0.15, lw=0)
    return ax.plot(x, g.estimate, **style, ms=MARKER_SIZE, lw=LINE_WIDTH, label=strategy_label(strategy))[0]


def coinciding(series: dict[str, tuple[np.ndarray, np.ndarray]], span: float) -> list[list[str]]:
    """Groups (two or more) of the named ``(x, y)`` series that coincide: same x, ``|Δy| ≤ COINCIDE·span``.

    ``x`` and ``y`` of a series: shape (n_points,) each (n_points may differ between series); ``span``: the
    y range drawn, in y's units.
    """
    groups: list[list[str]] = []
    for name, (x, y) in series.items():
        for grp in groups:
            gx, gy = series[grp[0]]
            if len(gx) == len(x) and np.allclose(gx, x) and np.nanmax(np.abs(gy - y)) <= COINCIDE * span:
                grp.append(name)
                break
        else:
            groups.append([name])
    return [g for g in groups if len(g) > 1]


def _coincide_note(groups: list[list[str]]) -> str:
    """The strategies whose lines coincide, a line per group ("" if none)."""
    return ";\n".join(" = ".join(strategy_label(s) for s in g) for g in groups) + (
        " (lines coincide)" if groups else ""
    )


def _strategy_lines(
    ax: Axes, sel: pd.DataFrame, x: str, metric: str, strategies: Sequence[str] | None
) -> str:
    """A line and a 95 % band per strategy of ``sel`` against column ``x`` (a fraction, drawn in %), each
    strategy its colour, line style and marker (:func:`glu.plots.style.strategy_style`). Of lines that
    coincide, the earlier drawn are wider with larger markers, so that each shows around the next.

    Returns the note naming the strategies whose lines coincide ("" if none).
    """
    series, lines = {}, {}
    for strategy, g in sel.groupby("strategy", sort=False):
        if strategies is None or strategy in strategies:
            g = g.sort_values(x)
            lines[strategy] = _line(ax, g[x].to_numpy() * 100, g, strategy)
            series[strategy] = (g[x].to_numpy(dtype=float), g.estimate.to_numpy(dtype=float))
    ax.set_ylabel(METRIC_LABEL.get(metric, metric))
    lo, hi = ax.get_ylim()
    groups = coinciding(series, hi - lo)
    for group in groups:
        for k, strategy in enumerate(reversed(group)):  # k: how many lines lie on this one
            lines[strategy].set_linewidth(LINE_WIDTH + 1.0 * k)
            lines[strategy].set_markersize(MARKER_SIZE + 1.8 * k)
    return _coincide_note(groups)


def _title(ax: Axes, first: str, note: str = "") -> None:
    """A panel's title: the lines of ``first``, then ``note``, each wrapped at :data:`TITLE_CHARS` into lines
    of even length (:func:`glu.plots.style.balanced_fill`)."""
    lines = [*first.split("\n"), *note.split("\n")] if note else first.split("\n")
    ax.set_title("\n".join(balanced_fill(line, TITLE_CHARS) for line in lines), fontsize=9)


def plot_early_recognition(
    ax: Axes,
    results: pd.DataFrame,
    target: str,
    metric: str = "accuracy",
    noise: float | None = None,
    viewpoint: str = "all",
    strategies: Sequence[str] | None = None,
    where: Mapping[str, Any] | None = None,
) -> Axes:
    """One metric against the observed fraction of the gesture, a line and a 95 % band per strategy."""
    sel = _pooled(results, noise, viewpoint, where)
    sel = sel[(sel.target == target) & (sel.metric == metric)]
    note = _strategy_lines(ax, sel, "fraction", metric, strategies)
    how = "all noise levels" if noise is None else f"noise {noise * 100:g} cm"
    ax.set_xlabel("gesture observed (%)")
    _title(ax, f"{target} {METRIC_LABEL.get(metric, metric)} ({how})\n{where_label(where)}", note)
    return ax


def plot_reliability(
    ax: Axes,
    reliability: pd.DataFrame,
    fraction: float = 1.0,
    strategies: Sequence[str] | None = None,
    noise: float | None = None,
    viewpoint: str = "all",
    where: Mapping[str, Any] | None = None,
    target: str = "effect",
) -> Axes:
    """Reliability diagram of a target (the effect ObjVel, or the action): how often the top value was
    right, against its probability, per calibration bin; each strategy its colour, line style and marker
    (:func:`glu.plots.style.strategy_style`), the marker's area growing with the share of the strategy's
    episodes in the bin (:func:`size_of_share` for a key). Lines drawn first are wider, so that one lying on
    another shows as a border around it."""
    sel = _pooled(reliability, noise, viewpoint, where)
    sel = sel[np.isclose(sel.fraction, fraction) & (sel.n > 0) & (sel.target == target)]
    ax.plot([0, 1], [0, 1], color="0.6", lw=0.8, ls=":")
    total = sel.groupby("strategy").n.transform("sum")
    series = {}
    drawn = [s for s in dict.fromkeys(sel.strategy) if strategies is None or s in strategies]
    for strategy, g in sel.assign(share=sel.n / total).groupby("strategy", sort=False):
        if strategy in drawn:
            style = strategy_style(strategy)
            marker = style.pop("marker")
            lw = 1.0 + 0.8 * (
                len(drawn) - 1 - drawn.index(strategy)
            )  # the first widest: overlaps stay visible
            ax.plot(g.confidence, g.accuracy, **style, lw=lw, label=strategy_label(strategy))
            ax.scatter(
                g.confidence,
                g.accuracy,
                s=size_of_share(g.share),
                color=style["color"],
                marker=marker,
                alpha=0.7,
                lw=0,
            )
            series[strategy] = (g.confidence.to_numpy(dtype=float), g.accuracy.to_numpy(dtype=float))
    ax.set_xlim(0.3, 1.0)
    ax.set_ylim(0.0, 1.0)
    what = "ObjVel value" if target == "effect" else "action"
    ax.set_xlabel(f"predicted probability of the top {what}")
    ax.set_ylabel("how often it was right")
    _title(
        ax,
        f"{target} calibration ({fraction:.0%} seen)\n{where_label(where)}",
        _coincide_note(coinciding(series, 1.0)),
    )
    return ax


def size_of_share(share):
    """Marker area (points²) of a calibration bin holding ``share`` of a strategy's episodes (at least 12,
    so that the smallest marker still shows its shape)."""
    return 12 + 200 * np.asarray(share, dtype=float)


def plot_differences(
    ax: Axes,
    differences: pd.DataFrame,
    pairs: Sequence[tuple[str, str, str, str]],
    fraction: float = 1.0,
    noise: float | None = None,
    viewpoint: str = "all",
    where: Mapping[str, Any] | None = None,
) -> Axes:
    """Paired differences with 95 % intervals, one row per ``(target, metric, strategy, baseline)``.

    The colour and marker are the strategy's (:func:`glu.plots.style.strategy_style`); a filled marker: the
    interval excludes 0 on the side where the metric improves (hollow: it does not). Each row's difference
    and interval are written in a column right of the axes, since the metrics (accuracy, nats, ECE) share one
    axis.
    """
    sel = _pooled(differences, noise, viewpoint, where)
    sel = sel[np.isclose(sel.fraction, fraction)]
    labels = []
    for i, (target, metric, strategy, baseline) in enumerate(pairs):
        row = pair(sel, target, metric, strategy, baseline)  # flipped if stored the other way round
        if row.empty:
            continue
        r = row.iloc[0]
        lo, hi = r.ci_low, r.ci_high
        c, marker = STRATEGY_COLORS.get(strategy, "black"), STRATEGY_MARKERS.get(strategy, "o")
        ax.plot([lo, hi], [i, i], color=c, lw=2)
        filled = c if _better(metric, lo, hi) else "white"
        ax.plot([r.difference], [i], marker=marker, ms=7, color=c, mfc=filled, ls="none")
        value = f"{r.difference:+.3f} [{lo:+.3f}, {hi:+.3f}]".replace("-", "−")
        ax.text(1.02, i, value, va="center", fontsize=7, color="0.2", transform=ax.get_yaxis_transform())
        better = "higher" if _higher(metric) else "lower"
        what = f"{target} {METRIC_LABEL.get(metric, metric)} ({better} is better)"
        labels.append((i, f"{what}: {strategy_label(strategy)} − {strategy_label(baseline)}"))
    ax.axvline(0, color="0.5", lw=0.8)
    ax.set_yticks([i for i, _ in labels], [t for _, t in labels], fontsize=7)
    ax.set_ylim(len(pairs) - 0.5, -0.5)
    ax.xaxis.set_major_locator(MaxNLocator(nbins=5))  # a narrow panel: at most six readable tick labels
    ax.set_xlabel("difference (95 % paired bootstrap interval)")
    ax.set_title(f"paired differences ({fraction:.0%} seen)\n{where_label(where)}", fontsize=9)
    return ax


def _higher(metric: str) -> bool:
    from glu.stats import HIGHER_IS_BETTER

    return HIGHER_IS_BETTER.get(metric, True)


def _better(metric: str, lo: float, hi: float) -> bool:
    return lo > 0 if _higher(metric) else hi < 0


def plot_by_viewpoint(
    ax: Axes,
    results: pd.DataFrame,
    target: str,
    metric: str,
    fraction: float = 1.0,
    strategies: Sequence[str] | None = None,
    where: Mapping[str, Any] | None = None,
) -> Axes:
    """One metric per viewpoint (pooled over noise) in one cell of the design (``where`` over the reference
    cell): a line with markers and 95 % error bars per strategy, each its colour, line style and marker
    (:func:`glu.plots.style.strategy_style`), set a little apart so that the error bars do not hide each
    other."""
    sel = metric_rows(_cell(results, {**REFERENCE_CELL, **(where or {})}), target, metric, fraction)
    sel = sel[sel.noise.isna() & (sel.viewpoint != "all")]
    views = viewpoints(sel)
    x = np.arange(len(views))
    strats = list(dict.fromkeys(sel.strategy))
    if strategies is not None:  # in the order asked for
        strats = [s for s in strategies if s in strats]
    for k, strategy in enumerate(strats):
        g = sel[sel.strategy == strategy].set_index("viewpoint").loc[views]
        dx = (k - (len(strats) - 1) / 2) * 0.06
        ax.errorbar(
            x + dx,
            g.estimate,
            yerr=[g.estimate - g.ci_low, g.ci_high - g.estimate],
            **strategy_style(strategy),
            ms=MARKER_SIZE,
            lw=1.2,
            capsize=2,
            label=strategy_label(strategy),
        )
    ax.set_xticks(x, views)
    ax.set_xlim(-0.4, len(views) - 0.6)
    ax.set_ylabel(METRIC_LABEL.get(metric, metric))
    _title(ax, f"{target} {METRIC_LABEL.get(metric, metric)} by viewpoint\n{where_label(where)}")
    ax.set_xlabel(f"viewpoint (all noise levels, {fraction:.0%} seen)")
    return ax


def plot_winners(ax: Axes, winners: pd.DataFrame, target: str, metric: str) -> Axes:
    """Which strategy wins each cell of the design for one target and metric: rows (action prior,
    inference network), columns the p_HMM readings; each cell coloured by the winner and naming it, with
    ``=`` before the initials of the strategies tied with it (:data:`INITIALS`;
    :func:`glu.studies.corpus_evaluation.findings.winners`)."""
    sel = winners[(winners.target == target) & (winners.metric == metric)].copy()
    sel["network"] = [
        "generating" if n == "generating" else f"learned {int(k)}"
        for n, k in zip(sel.inference_network, sel.learn_experiments, strict=True)
    ]
    rows = list(dict.fromkeys(zip(sel.action_prior, sel.network, strict=True)))
    cols = list(dict.fromkeys(sel.p_hmm))
    ax.set_xlim(-0.5, len(cols) - 0.5)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    for r in sel.itertuples():
        i, j = rows.index((r.action_prior, r.network)), cols.index(r.p_hmm)
        c = STRATEGY_COLORS.get(r.best, "0.5")
        ax.add_patch(plt_rectangle(j, i, c, alpha=0.35))
        tied = [INITIALS.get(t, t) for t in r.tied.split(", ") if t and t != r.best]
        ax.text(j, i + (0.12 if tied else 0.0), r.best, ha="center", va="center", fontsize=7, weight="bold")
        if tied:
            ax.text(j, i + 0.32, "= " + " ".join(tied), ha="center", va="center", fontsize=6.5)
    ax.set_xticks(range(len(cols)), cols, fontsize=7)
    ax.set_yticks(range(len(rows)), [f"{a} actions, {n}" for a, n in rows], fontsize=7)
    ax.set_title(f"{target}: {METRIC_LABEL.get(metric, metric)}, best (= no adjusted difference)", fontsize=9)
    ax.set_xlabel("p_HMM reading", fontsize=7)
    ax.tick_params(length=0)
    return ax


def winners_figure(winners: pd.DataFrame, shown: Sequence[tuple[str, str]]) -> Figure:
    """Which strategy wins each cell (:func:`plot_winners`), one panel per ``(target, metric)`` of ``shown``,
    two to a row, each as tall as its rows of action prior × network need."""
    rows = winners.groupby(list(CELL[:3])).ngroups
    nrows = -(-len(shown) // 2)
    fig, axes = plt.subplots(nrows, 2, figsize=(10, (0.9 * rows + 2.5) * nrows / 2), squeeze=False)
    for ax, (target, metric) in zip(axes.flat, shown, strict=False):
        plot_winners(ax, winners, target, metric)
    for ax in list(axes.flat)[len(shown) :]:
        fig.delaxes(ax)
    return fig


def plt_rectangle(x: float, y: float, color: Any, **look: Any) -> Any:
    """A cell of :func:`plot_winners` and :func:`findings_figure`: a unit square centred on (x, y) with a
    white edge (``look``: e.g. ``alpha``)."""
    from matplotlib.patches import Rectangle

    return Rectangle((x - 0.5, y - 0.5), 1, 1, facecolor=color, **look, edgecolor="white", lw=1.5)


def plot_segment_readings(ax: Axes, readings: pd.DataFrame) -> Axes:
    """p_HMM on held-out real segments
    (:func:`glu.studies.corpus_evaluation.p_hmm_readings.segment_readings`): for each reading, the top
    action's probability of every segment, filled when the segment was recognised, hollow when not."""
    order = list(dict.fromkeys(readings.reading))
    rng = np.random.default_rng(0)
    for k, (_, g) in enumerate(readings.groupby("reading", sort=False)):
        x = k + rng.uniform(-0.15, 0.15, len(g))
        ok = g.correct.to_numpy(dtype=bool)
        ax.scatter(x[ok], g.confidence[ok], color="#4C72B0", s=18, label="recognised" if k == 0 else None)
        ax.scatter(
            x[~ok],
            g.confidence[~ok],
            facecolor="white",
            edgecolor="#C44E52",
            s=18,
            label="missed" if k == 0 else None,
        )
        ax.hlines(
            g.correct.mean(), k - 0.3, k + 0.3, color="0.3", lw=1.2, label="accuracy" if k == 0 else None
        )
    ax.set_xticks(range(len(order)), order)
    ax.set_ylim(0.0, 1.05)
    ax.set_ylabel("p_HMM of the top action")
    ax.set_title("real segments, each left out", fontsize=9)
    return ax


INITIALS = {"gesture": "G", "network": "N", "hard": "H", "virtual": "V", "jeffrey": "J", "product": "P"}
"""The strategies' initials in :func:`plot_winners`."""
READING_STYLE = {
    "likelihood": ("#C44E52", "-"),
    "per-frame": ("#4C72B0", "--"),
    "calibrated": ("#55A868", "-."),
    "calibrated-matched": ("#8172B3", ":"),
}


def plot_p_hmm_reliability(
    ax: Axes,
    reliability: pd.DataFrame,
    fraction: float = 1.0,
    where: Mapping[str, Any] | None = None,
    viewpoint: str = "all",
) -> Axes:
    """Reliability diagram of p_HMM itself (target action, strategy gesture), one line per reading of p_HMM
    in the sweep (through the bins that hold at least 2 % of the gestures; marker area ∝ the bin's share);
    ``where`` picks the effects, action prior, network and features (not the reading)."""
    sel = reliability[
        (reliability.target == "action")
        & (reliability.strategy == "gesture")
        & reliability.noise.isna()
        & (reliability.viewpoint == viewpoint)
        & np.isclose(reliability.fraction, fraction)
        & (reliability.n > 0)
    ]
    sel = select(sel, where or {})
    ax.plot([0, 1], [0, 1], color="0.6", lw=0.8, ls=":")
    for reading, g in sel.groupby("p_hmm", sort=False):
        color, ls = READING_STYLE.get(reading, ("black", "-"))
        share = g.n / g.n.sum()
        many = g[share >= 0.02]  # the line joins bins holding at least 2 % of the gestures
        ax.plot(many.confidence, many.accuracy, color=color, ls=ls, lw=1.0, label=f"p_HMM {reading}")
        ax.scatter(g.confidence, g.accuracy, s=4 + 200 * share, color=color, alpha=0.7, lw=0)
    ax.set_xlim(0.3, 1.0)
    ax.set_ylim(0.0, 1.0)
    ax.set_xlabel("p_HMM of the top action")
    ax.set_ylabel("how often it was right")
    views = "all viewpoints" if viewpoint == "all" else f"seen {viewpoint}"
    ax.set_title(f"p_HMM on held-out synthetic gestures\n{views} ({fraction:.0%} seen)", fontsize=9)
    return ax


PANEL = (3.9, 3.0)
"""Inches: the size of one panel."""


def _grid(nrows: int, ncols: int, height: float = PANEL[1]) -> tuple[Figure, list]:
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(PANEL[0] * ncols, height * nrows), layout="constrained", squeeze=False
    )
    return fig, list(axes.flat)


def strategy_legend(
    fig: Figure,
    strategies: Sequence[str],
    extra: Sequence = (),
    ncols: int = 4,
    title: str | None = None,
    **look: Any,
) -> None:
    """One legend above the panels: a line with its marker per strategy, drawn as the panels draw it
    (:func:`glu.plots.style.strategy_style`; ``look`` overrides it, e.g. ``ls="-"``), then ``extra``
    handles; ``title`` above the entries."""
    handles = [
        Line2D([], [], **{**strategy_style(s), "ms": MARKER_SIZE, **look}, label=strategy_label(s))
        for s in strategies
    ]
    fig.legend(
        handles=[*handles, *extra],
        loc="outside upper center",
        ncols=ncols,
        fontsize=8,
        frameon=False,
        title=title,
        title_fontsize=8,
    )


def _drawn(table: pd.DataFrame, targets: Sequence[str]) -> list[str]:
    return list(dict.fromkeys(table[table.target.isin(targets)].strategy))


Cells = Sequence[Mapping[str, Any]]


def plot_by_viewpoint_and_features(
    ax: Axes,
    results: pd.DataFrame,
    target: str,
    metric: str,
    features: str,
    strategies: Sequence[str],
    fraction: float = 1.0,
    where: Mapping[str, Any] | None = None,
) -> Axes:
    """One metric per viewpoint (noise pooled) for one feature set of the recogniser
    (:func:`plot_by_viewpoint`), titled by the feature set alone: the figure names the rest of the cell."""
    plot_by_viewpoint(
        ax, results, target, metric, fraction, strategies, {**(where or {}), "features": features}
    )
    ax.set_title(f"{target} {METRIC_LABEL.get(metric, metric)}, {features} features", fontsize=9)
    ax.set_xlabel("")
    return ax


def viewpoints_figure(
    results: pd.DataFrame,
    features: Sequence[str],
    fraction: float = 1.0,
    where: Mapping[str, Any] | None = None,
) -> Figure:
    """Where the conclusion changes: the action's accuracy (top) and the effect's log-loss (bottom) per
    viewpoint, one column per feature set of the recogniser, in one cell (default the reference cell)."""
    action = ("gesture", "network", "product", "hard")
    effect = ("network", "hard", "virtual", "jeffrey", "true_action")
    fig, axes = _grid(2, len(features), height=2.9)
    for k, f in enumerate(features):
        plot_by_viewpoint_and_features(axes[k], results, "action", "accuracy", f, action, fraction, where)
        plot_by_viewpoint_and_features(
            axes[len(features) + k], results, "effect", "log_loss", f, effect, fraction, where
        )
    for row in (axes[: len(features)], axes[len(features) :]):  # one scale per row: feature sets compared
        lows, highs = zip(*(ax.get_ylim() for ax in row), strict=True)
        for ax in row:
            ax.set_ylim(min(lows), max(highs))
    cell = where_label({**(where or {}), "features": "raw"}).rsplit(", ", 1)[0]
    strategy_legend(
        fig,
        list(dict.fromkeys([*action, *effect])),
        ncols=4,
        title=f"{cell}; {fraction:.0%} of the gesture seen, noise pooled",
    )
    return fig


def findings_figure(counts: pd.DataFrame, columns: Sequence[tuple[str, str, str]]) -> Figure:
    """Where each finding holds: one row per finding, one column per condition ``(effects, viewpoint,
    features)`` (noise pooled); each cell writes ``holds/cells`` (adjusted verdicts; ``↓k``: reversed in k)
    and is shaded by the share of the cells where the finding holds (the reverse shaded below white)."""
    c = counts[counts.noise.isna()]
    findings = list(dict.fromkeys(c.finding))
    fig, ax = plt.subplots(
        figsize=(1.05 * len(columns) + 4.6, 0.42 * len(findings) + 1.6), layout="constrained"
    )
    cmap = plt.get_cmap("PuOr")
    for j, (effects, view, features) in enumerate(columns):
        for i, finding in enumerate(findings):
            r = c[
                (c.finding == finding)
                & (c.effects == effects)
                & (c.viewpoint == view)
                & (c.features == features)
            ]
            if r.empty:
                continue
            r = r.iloc[0]
            share = (r.better - r.worse) / max(r.cells, 1)
            face = cmap(0.5 + 0.5 * share)
            ax.add_patch(plt_rectangle(j, i, face))
            text = f"{int(r.better)}/{int(r.cells)}" + (f" ↓{int(r.worse)}" if r.worse else "")
            dark = 0.299 * face[0] + 0.587 * face[1] + 0.114 * face[2] < 0.5  # white text on dark cells
            ax.text(j, i, text, ha="center", va="center", fontsize=7, color="white" if dark else "black")
    ax.set_xlim(-0.5, len(columns) - 0.5)
    ax.set_ylim(len(findings) - 0.5, -0.5)
    labels = [
        f"{view}\n{features}" + ("" if effects == "action" else "\neffects ← gesture")
        for effects, view, features in columns
    ]
    ax.set_xticks(range(len(columns)), labels, fontsize=7)
    ax.set_yticks(range(len(findings)), [textwrap.fill(f, 55) for f in findings], fontsize=7)
    ax.tick_params(length=0)
    ax.set_title(
        "cells of the design where each finding holds (adjusted verdicts, noise pooled; ↓k: reversed in k)",
        fontsize=9,
    )
    return fig


def early_recognition_figure(results: pd.DataFrame, cells: Cells, viewpoint: str = "front") -> Figure:
    """Action accuracy (top) and effect log-loss (bottom) against the fraction of the gesture seen, at one
    viewpoint (noise pooled)."""
    fig, axes = _grid(2, len(cells))
    for k, cell in enumerate(cells):
        plot_early_recognition(axes[k], results, "action", "accuracy", viewpoint=viewpoint, where=cell)
        plot_early_recognition(
            axes[len(cells) + k], results, "effect", "log_loss", viewpoint=viewpoint, where=cell
        )
    strategy_legend(fig, _drawn(results, ("action", "effect")))
    return fig


def calibration_figure(
    reliability: pd.DataFrame,
    results: pd.DataFrame,
    cells: Cells,
    fraction: float = 1.0,
    strategies: Sequence[str] = ("network", "hard", "virtual", "jeffrey", "true_action"),
    by_viewpoint: Sequence[str] = ("gesture", "network", "hard", "product"),
    viewpoint: str = "front",
) -> Figure:
    """Reliability diagrams of the effect in the first two cells at one viewpoint (top); the effect's ECE
    and the action's accuracy per viewpoint in the first cell (bottom). A key gives the marker sizes."""
    fig, axes = _grid(2, 2, height=3.2)
    for ax, cell in zip(axes[:2], cells[:2], strict=False):
        plot_reliability(ax, reliability, fraction, strategies=strategies, viewpoint=viewpoint, where=cell)
    plot_by_viewpoint(axes[2], results, "effect", "ece", fraction, strategies=strategies, where=cells[0])
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
    viewpoint: str = "front",
) -> Figure:
    """Paired differences at one viewpoint (noise pooled), one panel per cell of the design (stacked), with
    a key to the strategies' markers and to filled and hollow ones."""
    fig, axes = _grid(len(cells), 1, height=2.9)
    fig.set_figwidth(9.0)
    for ax, cell in zip(axes, cells, strict=True):
        plot_differences(ax, differences, pairs, fraction, viewpoint=viewpoint, where=cell)
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
    strategy_legend(fig, list(dict.fromkeys(p[2] for p in pairs)), marks, ncols=3, ls="-", ms=6)
    return fig


def p_hmm_calibration_figure(
    reliability: pd.DataFrame,
    fraction: float = 1.0,
    where: Mapping[str, Any] | None = None,
    segments: pd.DataFrame | None = None,
    viewpoints: Sequence[str] = ("front",),
) -> Figure:
    """p_HMM's own reliability on the corpus's held-out synthetic gestures, one line per reading, a panel per
    viewpoint, and, given the real segments' readings, p_HMM on each segment left out; one legend above."""
    views = [v for v in viewpoints if v in set(reliability.viewpoint)] or ["all"]
    fig, axes = _grid(1, len(views) + (segments is not None), height=3.4)
    for ax, view in zip(axes, views, strict=False):
        plot_p_hmm_reliability(ax, reliability, fraction, where=where, viewpoint=view)
    drawn = set(reliability.p_hmm)
    handles = [
        Line2D([], [], color=c, ls=ls, marker="o", ms=3, label=f"p_HMM {reading}")
        for reading, (c, ls) in READING_STYLE.items()
        if reading in drawn
    ]
    if segments is not None:
        plot_segment_readings(axes[len(views)], segments)
        handles += axes[len(views)].get_legend_handles_labels()[0]
    fig.legend(handles=handles, loc="outside upper center", ncols=4, fontsize=8, frameon=False)
    return fig
