"""The corpus evaluation's metrics with their intervals, from sums that stream over chunks of episodes.

A corpus of a million episodes cannot be resampled as a whole: each chunk keeps the Poisson-bootstrap sums of
its per-episode statistics at two levels, recogniser seeds and episodes (:mod:`glu.stats`: each episode's
weight in replicate ``b`` is Poisson(``c_{b,k}``), ``c_{b,k}`` the number of copies of its seed ``k``), and
every metric of replicate ``b`` is computed from the merged sums ``S_b`` exactly as the estimate is from
``S_0``:

* a mean (accuracy, log-loss, Brier, description correctness) is ``S_b[stat] / S_b[n]``;
* the expected calibration error (top label, equal-width bins) is ``Σ_bins |S_b[correct_bin] −
  S_b[confidence_bin]| / S_b[n]``.

The ECE is biased upwards by sampling noise, its replicates more so: for a well-calibrated predictor the
interval can sit mostly above the estimate. Because the weights belong to episodes (the same for every
strategy, fraction and reading of an episode), the difference of two strategies is resampled *paired*:
:func:`paired_differences` takes the percentiles of the replicates' differences
(:func:`glu.stats.verdict`).

:func:`metrics`, :func:`paired_differences` and :func:`reliability` turn merged sums (one row per
condition and replicate) into tidy tables.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.stats import HIGHER_IS_BETTER, percentile_interval, verdict

BOOT_KEY = 2
"""Spawn key of a chunk's bootstrap weights."""
SEEDS_KEY = 3
"""Spawn key of the seed-level counts of a two-level bootstrap."""
MEAN_METRICS: dict[str, str] = {"correct": "accuracy", "log_loss": "log_loss", "brier": "brier"}
"""Per-episode statistic → the metric that is its mean."""


class Cells(NamedTuple):
    """The metric cells of a set of statistics: what each is, and how it is computed from the sums.

    Attributes
    ----------
    keys : DataFrame, one row per cell: target, strategy, fraction, metric
    mean : int array — for each cell, the statistic whose mean it is (−1 for an ECE cell)
    conf, correct : int arrays, shape (n_cells, n_bins) — an ECE cell's bin statistics (−1 elsewhere)
    """

    keys: pd.DataFrame
    mean: np.ndarray
    conf: np.ndarray
    correct: np.ndarray


def metric_cells(columns: pd.DataFrame) -> Cells:
    """The cells of :func:`metric_values` for statistics described by ``columns``, in their order."""
    cells = columns.iloc[1:]
    plain = cells[cells["bin"] < 0]
    keys = [(r.target, r.strategy, r.fraction, MEAN_METRICS.get(r.stat, r.stat)) for r in plain.itertuples()]
    mean = list(plain.index)
    binned = cells[cells["bin"] >= 0]
    n_bins = int(binned["bin"].max()) + 1 if len(binned) else 0
    conf, corr = [[-1] * n_bins for _ in mean], [[-1] * n_bins for _ in mean]
    for (target, strategy, fraction), g in binned.groupby(["target", "strategy", "fraction"], sort=False):
        keys.append((target, strategy, fraction, "ece"))
        mean.append(-1)
        conf.append(list(g.index[g.stat == "bin_confidence"]))
        corr.append(list(g.index[g.stat == "bin_correct"]))
    frame = pd.DataFrame(keys, columns=["target", "strategy", "fraction", "metric"])
    as_array = lambda x: np.array(x, dtype=np.intp).reshape(len(keys), n_bins)  # noqa: E731
    return Cells(frame, np.array(mean, dtype=np.intp), as_array(conf), as_array(corr))


def metric_values(sums: np.ndarray, columns: pd.DataFrame | Cells) -> np.ndarray:
    """Every metric of every replicate, shape (B + 1, n_cells), cells as :func:`metric_cells` lists them.

    Parameters
    ----------
    sums : array, shape (B + 1, K) — merged sums (row 0 the estimate)
    columns : the statistics' description
        (:func:`glu.studies.corpus_evaluation.evaluation.statistic_columns`), or its :func:`metric_cells`
    """
    cells = columns if isinstance(columns, Cells) else metric_cells(columns)
    K = int(max(cells.mean.max(initial=0), cells.conf.max(initial=0), cells.correct.max(initial=0))) + 1
    if sums.shape[1] < K:
        raise DataError(f"{sums.shape[1]} sums for {K} statistics: the chunks do not match the settings")
    n = sums[:, :1]
    out = np.empty((len(sums), len(cells.mean)))
    with np.errstate(invalid="ignore", divide="ignore"):
        plain = cells.mean >= 0
        out[:, plain] = sums[:, cells.mean[plain]] / n
        if (~plain).any():
            conf = sums[:, cells.conf[~plain]]  # (B + 1, n_ece, n_bins)
            corr = sums[:, cells.correct[~plain]]
            out[:, ~plain] = np.abs(corr - conf).sum(axis=2) / n
    return out


def metrics(sums: pd.DataFrame, columns: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """Estimates and 95 % intervals of every metric, per group of conditions.

    Parameters
    ----------
    sums : one row per (condition, replicate): the factor columns named in ``by`` (and others, pooled
        over), ``replicate`` (0 = estimate), and the K statistics as columns ``s0 … s{K-1}``
    columns : the statistics' description
    by : the factors to keep (e.g. ``["noise", "viewpoint"]``); the others are pooled (summed)

    Returns
    -------
    tidy DataFrame: the columns of ``by``, target, strategy, fraction, metric, estimate, ci_low, ci_high,
    n_episodes
    """
    cells = metric_cells(columns)
    parts = []
    for key, g in _groups(sums, by):
        S = _stat_matrix(g, len(columns))
        vals = metric_values(S, cells)
        lo, hi = percentile_interval(vals[1:])
        part = cells.keys.copy()
        for name, v in zip(by, key, strict=True):
            part.insert(len(part.columns) - 4, name, v)
        part["estimate"], part["ci_low"], part["ci_high"], part["n_episodes"] = (
            vals[0],
            lo,
            hi,
            float(S[0, 0]),
        )
        parts.append(part)
    cols = [*by, "target", "strategy", "fraction", "metric", "estimate", "ci_low", "ci_high", "n_episodes"]
    return pd.concat(parts, ignore_index=True)[cols] if parts else pd.DataFrame(columns=cols)


def paired_differences(sums: pd.DataFrame, columns: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """Differences between strategies on the same episodes, with paired bootstrap intervals.

    Returns
    -------
    tidy DataFrame: the columns of ``by``, target, fraction, metric, strategy, baseline, difference
    (strategy − baseline), ci_low, ci_high, better (the interval excludes 0 on the side where the metric
    improves), verdict (``better``, ``worse`` or ``no difference``: :func:`verdict`), for every pair of
    strategies predicting the same target (strategy after baseline in the settings' order)
    """
    cells = metric_cells(columns)
    k = cells.keys
    first, second = [], []
    for _, g in k.groupby(["target", "fraction", "metric"], sort=False):
        idx = list(g.index)
        for i, a in enumerate(idx):
            first += [a] * (len(idx) - i - 1)
            second += idx[i + 1 :]
    first, second = np.array(first, dtype=np.intp), np.array(second, dtype=np.intp)
    pairs = pd.DataFrame(
        {
            "target": k.target.to_numpy()[first],
            "fraction": k.fraction.to_numpy()[first],
            "metric": k.metric.to_numpy()[first],
            "strategy": k.strategy.to_numpy()[second],
            "baseline": k.strategy.to_numpy()[first],
        }
    )
    up = pairs.metric.map(lambda m: HIGHER_IS_BETTER.get(m, True)).to_numpy(dtype=bool)
    parts = []
    for key, g in _groups(sums, by):
        vals = metric_values(_stat_matrix(g, len(columns)), cells)
        d = vals[:, second] - vals[:, first]
        lo, hi = percentile_interval(d[1:])
        part = pairs.copy()
        for j, (name, v) in enumerate(zip(by, key, strict=True)):
            part.insert(j, name, v)
        part["difference"], part["ci_low"], part["ci_high"] = d[0], lo, hi
        part["better"] = np.where(up, lo > 0, hi < 0)
        part["verdict"] = [verdict(a, b, u) for a, b, u in zip(lo, hi, up, strict=True)]
        parts.append(part)
    cols = [
        *by,
        "target",
        "fraction",
        "metric",
        "strategy",
        "baseline",
        "difference",
        "ci_low",
        "ci_high",
        "better",
        "verdict",
    ]
    return pd.concat(parts, ignore_index=True)[cols] if parts else pd.DataFrame(columns=cols)


def reliability(sums: pd.DataFrame, columns: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """The reliability diagrams of the calibration bins (the estimate, row 0 of the sums).

    Returns
    -------
    tidy DataFrame: the columns of ``by``, target, strategy, fraction, bin, lower, upper (the bin's
    confidence range), n (episodes in the bin), confidence (their mean top-label confidence), accuracy
    (how often that label was right)
    """
    cols = [*by, "target", "strategy", "fraction", "bin", "lower", "upper", "n", "confidence", "accuracy"]
    binned = columns[columns["bin"] >= 0]
    if binned.empty:
        return pd.DataFrame(columns=cols)
    n_bins = int(binned["bin"].max()) + 1
    stats = {st: binned[binned.stat == st] for st in ("bin_n", "bin_confidence", "bin_correct")}
    base = stats["bin_n"][["target", "strategy", "fraction", "bin"]].reset_index(drop=True)
    base["lower"], base["upper"] = base["bin"] / n_bins, (base["bin"] + 1) / n_bins
    parts = []
    for key, g in _groups(sums, by):
        s0 = _stat_matrix(g, len(columns))[0]
        part = base.copy()
        for j, (name, v) in enumerate(zip(by, key, strict=True)):
            part.insert(j, name, v)
        cnt = s0[stats["bin_n"].index]
        with np.errstate(invalid="ignore", divide="ignore"):
            part["n"] = cnt
            part["confidence"] = s0[stats["bin_confidence"].index] / cnt
            part["accuracy"] = s0[stats["bin_correct"].index] / cnt
        parts.append(part)
    return pd.concat(parts, ignore_index=True)[cols]


def _stat_matrix(g: pd.DataFrame, k: int) -> np.ndarray:
    """The summed statistics of a group, by replicate: shape (B + 1, K)."""
    cols = [f"s{i}" for i in range(k)]
    return g.groupby("replicate", sort=True)[cols].sum().to_numpy()


def _groups(sums: pd.DataFrame, by: Sequence[str]):
    if not by:
        yield (), sums
        return
    for key, g in sums.groupby(list(by), sort=True):
        yield (key if isinstance(key, tuple) else (key,)), g
