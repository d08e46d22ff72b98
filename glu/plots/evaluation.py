"""Figures of the corpus evaluation: which fusion strategy wins where, with 95 % intervals.

Every function draws the tables of :mod:`glu.sweep` (``results``, ``differences``, ``reliability``) on the
axes it is given and returns them. In those tables a noise of NaN means "pooled over the noise levels"
and a viewpoint ``"all"`` "pooled over the viewpoints"; ``posterior`` picks how p_HMM was read from the
HMMs (:data:`glu.experiments.corpus.POSTERIORS`). Strategies whose lines coincide are named in the panel's
title, so that a line hidden under another is not missed; the legends are drawn once per figure
(:mod:`glu.plots.corpus`).
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

STRATEGY_COLORS = {
    "gesture": "#8C8C8C",
    "network": "#937860",
    "hard": "#C44E52",
    "virtual": "#4C72B0",
    "jeffrey": "#55A868",
    "product": "#DD8452",
    "true_action": "#222222",
}
STRATEGY_STYLE = {"true_action": ":", "network": "--", "gesture": "--"}
STRATEGY_LABELS = {
    "gesture": "gesture (HMMs alone)",
    "network": "network alone",
    "hard": "hard decision",
    "virtual": "virtual evidence",
    "jeffrey": "Jeffrey's rule",
    "product": "product rule",
    "true_action": "true action given",
}
"""How figures name the strategies of :mod:`glu.experiments.corpus` (``jeffrey`` is Jeffrey's rule)."""
POSTERIOR_LABELS = {"likelihood": r"$p_{HMM}$ from the likelihoods", "per_frame": r"$p_{HMM}$ per frame"}
"""How figures name the ways of reading p_HMM (:data:`glu.experiments.corpus.POSTERIORS`)."""
METRIC_LABEL = {
    "accuracy": "accuracy",
    "log_loss": "log-loss (nats)",
    "brier": "Brier score",
    "ece": "ECE",
    "verb": "verb right",
    "object": "object right",
    "effect": "effect right",
    "all": "sentence right",
}
COINCIDE = 0.01
"""Lines closer than this fraction of the axis' range at every point coincide (and the title says so)."""


def strategy_label(strategy: str) -> str:
    """A strategy as figures name it (:data:`STRATEGY_LABELS`)."""
    return STRATEGY_LABELS.get(strategy, strategy)


def posterior_label(posterior: str) -> str:
    """A way of reading p_HMM as figures name it (:data:`POSTERIOR_LABELS`)."""
    return POSTERIOR_LABELS.get(posterior, posterior)


def _pooled(frame: pd.DataFrame, noise: float | None, viewpoint: str, posterior: str) -> pd.DataFrame:
    sel = (frame.viewpoint == viewpoint) & (frame.posterior == posterior)
    return frame[sel & (frame.noise.isna() if noise is None else np.isclose(frame.noise, noise))]


def _line(ax: Axes, x: np.ndarray, g: pd.DataFrame, strategy: str) -> None:
    c = STRATEGY_COLORS.get(strategy, "black")
    ls = STRATEGY_STYLE.get(strategy, "-")
    ax.plot(x, g.estimate, color=c, ls=ls, marker="o", ms=3, lw=1.3, label=strategy_label(strategy))
    ax.fill_between(x, g.ci_low, g.ci_high, color=c, alpha=0.15, lw=0)


def coinciding(series: dict[str, tuple[np.ndarray, np.ndarray]], span: float) -> list[list[str]]:
    """Groups (two or more) of the named ``(x, y)`` series that coincide: same x, |Δy| ≤ COINCIDE·span."""
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
    return "; ".join(" = ".join(strategy_label(s) for s in g) for g in groups) + (
        " (lines coincide)" if groups else ""
    )


def _strategy_lines(
    ax: Axes, sel: pd.DataFrame, x: str, metric: str, strategies: Sequence[str] | None
) -> str:
    """A line and a 95 % band per strategy of ``sel`` against column ``x`` (a fraction, drawn in %).

    Returns the note naming the strategies whose lines coincide ("" if none).
    """
    series = {}
    for strategy, g in sel.groupby("strategy", sort=False):
        if strategies is None or strategy in strategies:
            g = g.sort_values(x)
            _line(ax, g[x].to_numpy() * 100, g, strategy)
            series[strategy] = (g[x].to_numpy(dtype=float), g.estimate.to_numpy(dtype=float))
    ax.set_ylabel(METRIC_LABEL.get(metric, metric))
    lo, hi = ax.get_ylim()
    return _coincide_note(coinciding(series, hi - lo))


def _title(ax: Axes, first: str, note: str) -> None:
    ax.set_title(first + ("\n" + textwrap.fill(note, 60) if note else ""), fontsize=9)


def plot_metric_vs_noise(
    ax: Axes,
    results: pd.DataFrame,
    target: str,
    metric: str,
    fraction: float = 1.0,
    viewpoint: str = "all",
    strategies: Sequence[str] | None = None,
    posterior: str = "likelihood",
) -> Axes:
    """One metric of one target against the sensor noise (m), a line and a 95 % band per strategy."""
    sel = results[
        (results.target == target)
        & (results.metric == metric)
        & np.isclose(results.fraction, fraction)
        & (results.viewpoint == viewpoint)
        & results.noise.notna()
        & (results.posterior == posterior)
    ]
    note = _strategy_lines(ax, sel, "noise", metric, strategies)
    where = "all viewpoints" if viewpoint == "all" else viewpoint
    first = f"{target} {METRIC_LABEL.get(metric, metric)}, {posterior_label(posterior)}"
    _title(ax, f"{first}\n({where}, {fraction:.0%} of the gesture seen)", note)
    ax.set_xlabel("sensor noise (cm)")
    return ax


def plot_early_recognition(
    ax: Axes,
    results: pd.DataFrame,
    target: str,
    metric: str = "accuracy",
    noise: float | None = None,
    viewpoint: str = "all",
    strategies: Sequence[str] | None = None,
    posterior: str = "likelihood",
) -> Axes:
    """One metric against the observed fraction of the gesture, a line and a 95 % band per strategy."""
    sel = _pooled(results, noise, viewpoint, posterior)
    sel = sel[(sel.target == target) & (sel.metric == metric)]
    note = _strategy_lines(ax, sel, "fraction", metric, strategies)
    how = "all noise levels" if noise is None else f"noise {noise * 100:g} cm"
    ax.set_xlabel("gesture observed (%)")
    _title(ax, f"{target} {METRIC_LABEL.get(metric, metric)}, {posterior_label(posterior)}\n({how})", note)
    return ax


def plot_reliability(
    ax: Axes,
    reliability: pd.DataFrame,
    fraction: float = 1.0,
    strategies: Sequence[str] | None = None,
    noise: float | None = None,
    viewpoint: str = "all",
    posterior: str = "likelihood",
) -> Axes:
    """Reliability diagram of the effect (ObjVel): how often the top value was right, against its
    probability, per calibration bin; marker area ∝ the share of the strategy's episodes in the bin
    (:func:`size_of_share` for a key). Lines drawn first are wider, so that one lying on another shows
    as a border around it."""
    sel = _pooled(reliability, noise, viewpoint, posterior)
    sel = sel[np.isclose(sel.fraction, fraction) & (sel.n > 0)]
    ax.plot([0, 1], [0, 1], color="0.6", lw=0.8, ls=":")
    total = sel.groupby("strategy").n.transform("sum")
    series = {}
    drawn = [s for s in dict.fromkeys(sel.strategy) if strategies is None or s in strategies]
    for strategy, g in sel.assign(share=sel.n / total).groupby("strategy", sort=False):
        if strategy in drawn:
            c = STRATEGY_COLORS.get(strategy, "black")
            ls = STRATEGY_STYLE.get(strategy, "-")
            lw = 1.0 + 0.8 * (
                len(drawn) - 1 - drawn.index(strategy)
            )  # the first widest: overlaps stay visible
            ax.plot(g.confidence, g.accuracy, color=c, lw=lw, ls=ls, label=strategy_label(strategy))
            ax.scatter(g.confidence, g.accuracy, s=size_of_share(g.share), color=c, alpha=0.7, lw=0)
            series[strategy] = (g.confidence.to_numpy(dtype=float), g.accuracy.to_numpy(dtype=float))
    ax.set_xlim(0.3, 1.0)
    ax.set_ylim(0.0, 1.0)
    ax.set_xlabel("predicted probability of the top ObjVel value")
    ax.set_ylabel("how often it was right")
    _title(
        ax,
        f"effect calibration ({fraction:.0%} seen), {posterior_label(posterior)}",
        _coincide_note(coinciding(series, 1.0)),
    )
    return ax


def size_of_share(share):
    """Marker area (points²) of a calibration bin holding ``share`` of a strategy's episodes."""
    return 4 + 200 * np.asarray(share, dtype=float)


def plot_differences(
    ax: Axes,
    differences: pd.DataFrame,
    pairs: Sequence[tuple[str, str, str, str]],
    fraction: float = 1.0,
    noise: float | None = None,
    viewpoint: str = "all",
    posterior: str = "likelihood",
) -> Axes:
    """Paired differences with 95 % intervals, one row per ``(target, metric, strategy, baseline)``.

    The colour is the strategy's; a filled marker: the interval excludes 0 on the side where the metric
    improves (hollow: it does not). Each row's difference and interval are written in a column right of
    the axes, since the metrics (accuracy, nats, ECE) share one axis.
    """
    sel = _pooled(differences, noise, viewpoint, posterior)
    sel = sel[np.isclose(sel.fraction, fraction)]
    labels = []
    for i, (target, metric, strategy, baseline) in enumerate(pairs):
        row = sel[
            (sel.target == target)
            & (sel.metric == metric)
            & (sel.strategy == strategy)
            & (sel.baseline == baseline)
        ]
        sign = 1.0
        if row.empty:  # stored the other way round
            row = sel[
                (sel.target == target)
                & (sel.metric == metric)
                & (sel.strategy == baseline)
                & (sel.baseline == strategy)
            ]
            sign = -1.0
        if row.empty:
            continue
        r = row.iloc[0]
        lo, hi = sorted((sign * r.ci_low, sign * r.ci_high))
        c = STRATEGY_COLORS.get(strategy, "black")
        ax.plot([lo, hi], [i, i], color=c, lw=2)
        ax.plot(
            [sign * r.difference], [i], marker="o", color=c, mfc=c if _better(metric, lo, hi) else "white"
        )
        value = f"{sign * r.difference:+.3f} [{lo:+.3f}, {hi:+.3f}]".replace("-", "−")
        ax.text(1.02, i, value, va="center", fontsize=7, color="0.2", transform=ax.get_yaxis_transform())
        better = "higher" if _higher(metric) else "lower"
        what = f"{target} {METRIC_LABEL.get(metric, metric)} ({better} is better)"
        labels.append((i, f"{what}: {strategy_label(strategy)} − {strategy_label(baseline)}"))
    ax.axvline(0, color="0.5", lw=0.8)
    ax.set_yticks([i for i, _ in labels], [t for _, t in labels], fontsize=7)
    ax.set_ylim(len(pairs) - 0.5, -0.5)
    ax.set_xlabel("difference (95 % paired bootstrap interval)")
    ax.set_title(f"paired differences ({fraction:.0%} seen), {posterior_label(posterior)}", fontsize=9)
    return ax


def _higher(metric: str) -> bool:
    from glu.experiments.intervals import HIGHER_IS_BETTER

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
    posterior: str = "likelihood",
) -> Axes:
    """One metric per viewpoint (pooled over noise), grouped bars with 95 % intervals per strategy."""
    sel = results[
        (results.target == target)
        & (results.metric == metric)
        & np.isclose(results.fraction, fraction)
        & results.noise.isna()
        & (results.viewpoint != "all")
        & (results.posterior == posterior)
    ]
    views = list(dict.fromkeys(sel.viewpoint))
    strats = [s for s in dict.fromkeys(sel.strategy) if strategies is None or s in strategies]
    width = 0.8 / max(len(strats), 1)
    for k, strategy in enumerate(strats):
        g = sel[sel.strategy == strategy].set_index("viewpoint").loc[views]
        x = np.arange(len(views)) + (k - (len(strats) - 1) / 2) * width
        ax.bar(
            x,
            g.estimate,
            width,
            color=STRATEGY_COLORS.get(strategy, "black"),
            label=strategy_label(strategy),
            yerr=[g.estimate - g.ci_low, g.ci_high - g.estimate],
            error_kw={"lw": 0.8},
        )
    ax.set_xticks(np.arange(len(views)), views)
    ax.set_ylabel(METRIC_LABEL.get(metric, metric))
    ax.set_title(
        f"{target} {METRIC_LABEL.get(metric, metric)} by viewpoint, {posterior_label(posterior)}", fontsize=9
    )
    ax.set_xlabel(f"viewpoint (all noise levels, {fraction:.0%} seen)")
    return ax
