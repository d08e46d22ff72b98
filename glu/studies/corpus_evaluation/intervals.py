"""The corpus evaluation's metrics with their intervals, from sums that stream over chunks of episodes.

A corpus of a million episodes cannot be resampled as a whole: each chunk keeps the Poisson-bootstrap sums of
its per-episode statistics at two levels, recogniser seeds and episodes (:mod:`glu.stats`: each episode's
weight in replicate ``b`` is Poisson(``c_{b,k}``), ``c_{b,k}`` the number of copies of its seed ``k``), and
every metric of replicate ``b`` is computed from the merged sums ``S_b`` exactly as the estimate is from
``S_0``:

* a mean (accuracy, log-loss, Brier, the words' mean log-loss and Brier) is ``S_b[stat] / S_b[n]``;
* the expected calibration error (top label, equal-width bins), binned: ``Σ_bins |S_b[correct_bin] −
  S_b[confidence_bin]| / S_b[n]``.

A mean's interval is the percentile interval of its replicates. **The ECE is corrected for its bias.** The
binned ECE is biased upwards by sampling noise (an absolute value of a noisy difference), and a bootstrap
replicate, a resample of the sample, is biased upwards once more: for a well-calibrated predictor the
replicates sit mostly above the plug-in estimate, and their percentile interval can leave the estimate out
(8 of 288 lines of a sweep's summary did before). So an ECE, and a difference of two ECEs, is reported
with Efron's bootstrap bias correction, ``θ̃ = 2 θ̂ − mean(θ*)``, and the basic bootstrap interval
``[2 θ̂ − q_97.5, 2 θ̂ − q_2.5]`` (Davison & Hinkley 1997, §2.4 and §5.2), which is the percentile interval
with the bias removed; an ECE and its interval are clipped at 0. The corrected estimate lies inside its
interval unless the replicates' mean lies outside their own 2.5–97.5 % range (tested). The plug-in value is
kept as ``ece_plugin``.

Because the weights belong to episodes (the same for every strategy, fraction and reading of an episode),
the difference of two strategies is resampled *paired*: :func:`paired_differences` takes the interval of
the replicates' differences (:func:`glu.stats.verdict`) and their two-sided bootstrap p-value
(:func:`glu.stats.bootstrap_p_value`, against 0; for an ECE difference, against ``2 d̂`` as the basic
interval implies), which a family's multiplicity adjustment takes.

:func:`metrics`, :func:`paired_differences` and :func:`reliability` turn merged sums (one row per
condition and replicate) into tidy tables.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.stats import bootstrap_p_value, percentile_interval, verdict
from glu.studies.corpus_evaluation.findings import higher_is_better

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


def estimates_and_intervals(
    vals: np.ndarray, corrected: np.ndarray, clip: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Estimates and 95 % intervals of the columns of ``vals`` (shape (B + 1, n), row 0 the estimate): the
    plug-in estimate and the percentile interval, or where ``corrected`` the bias-corrected estimate and the
    basic interval (module docstring), clipped at 0 with ``clip``."""
    est = vals[0].copy()
    lo, hi = percentile_interval(vals[1:])
    if corrected.any() and len(vals) > 1:
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            mean = np.nanmean(vals[1:, corrected], axis=0)
        e, a, b = vals[0, corrected], lo[corrected], hi[corrected]
        est[corrected], lo[corrected], hi[corrected] = 2 * e - mean, 2 * e - b, 2 * e - a
        if clip:
            for x in (est, lo, hi):
                x[corrected] = np.maximum(x[corrected], 0.0)
    return est, lo, hi


class Pairs(NamedTuple):
    """Every pair of strategies predicting the same target, fraction and metric (strategy after baseline in
    the settings' order): their description and the cells they compare."""

    keys: pd.DataFrame
    first: np.ndarray
    second: np.ndarray
    up: np.ndarray
    ece: np.ndarray


def difference_pairs(cells: Cells) -> Pairs:
    """The :class:`Pairs` of a set of metric cells (columns target, fraction, metric, strategy, baseline)."""
    k = cells.keys
    first, second = [], []
    for _, g in k.groupby(["target", "fraction", "metric"], sort=False):
        idx = list(g.index)
        for i, a in enumerate(idx):
            first += [a] * (len(idx) - i - 1)
            second += idx[i + 1 :]
    a, b = np.array(first, dtype=np.intp), np.array(second, dtype=np.intp)
    keys = pd.DataFrame(
        {
            "target": k.target.to_numpy()[a],
            "fraction": k.fraction.to_numpy()[a],
            "metric": k.metric.to_numpy()[a],
            "strategy": k.strategy.to_numpy()[b],
            "baseline": k.strategy.to_numpy()[a],
        }
    )
    up = higher_is_better(keys.metric)
    return Pairs(keys, a, b, up, (keys.metric == "ece").to_numpy())


def metric_block(S: np.ndarray, cells: Cells) -> dict[str, np.ndarray]:
    """Every metric's estimate and interval from one group's summed statistics ``S`` (shape (B + 1, K)):
    columns estimate, ci_low, ci_high, ece_plugin, n_episodes (one value per cell)."""
    vals = metric_values(S, cells)
    ece = cells.mean < 0
    est, lo, hi = estimates_and_intervals(vals, ece)
    n = np.full(len(est), float(S[0, 0]))
    return {"estimate": est, "ci_low": lo, "ci_high": hi, "ece_plugin": np.where(ece, vals[0], np.nan),
            "n_episodes": n}  # fmt: skip


def difference_block(S: np.ndarray, cells: Cells, pairs: Pairs) -> dict[str, np.ndarray]:
    """Every pair's paired difference from one group's summed statistics ``S`` (shape (B + 1, K)): columns
    difference, ci_low, ci_high, p_value, better, verdict, each of shape (n_pairs,)."""
    vals = metric_values(S, cells)
    d = vals[:, pairs.second] - vals[:, pairs.first]
    est, lo, hi = estimates_and_intervals(d, pairs.ece, clip=False)
    null = np.where(pairs.ece, 2 * d[0], 0.0)  # the basic interval excludes 0 ⇔ the replicates exclude 2 d̂
    p = bootstrap_p_value(d - null[None, :])
    better = np.where(pairs.up, lo > 0, hi < 0)
    verdicts = np.array([verdict(a, b, u) for a, b, u in zip(lo, hi, pairs.up, strict=True)], dtype=object)
    return {"difference": est, "ci_low": lo, "ci_high": hi, "p_value": p, "better": better,
            "verdict": verdicts}  # fmt: skip


Blocks = list[tuple[tuple, dict[str, np.ndarray]]]
"""Each group's key (its ``by`` values) and block of columns."""


def block_frame(keys: pd.DataFrame, by: Sequence[str], groups: Blocks) -> pd.DataFrame:
    """One frame of the blocks of many groups (:func:`metric_block`, :func:`difference_block`,
    :func:`reliability_block`): each group's ``by`` values, the ``keys`` of its rows, the blocks' columns."""
    if not groups:
        return pd.DataFrame(columns=[*by, *keys.columns])
    n = len(keys)
    out = {name: np.repeat(np.array([g[0][j] for g in groups]), n) for j, name in enumerate(by)}
    for c in keys.columns:
        out[c] = np.tile(keys[c].to_numpy(), len(groups))
    for c in groups[0][1]:
        out[c] = np.concatenate([g[1][c] for g in groups])
    return pd.DataFrame(out)


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
    tidy DataFrame: the columns of ``by``, target, strategy, fraction, metric, estimate, ci_low, ci_high
    (for the ECE the bias-corrected estimate and basic interval), ece_plugin (the ECE's plug-in estimate;
    NaN for other metrics), n_episodes
    """
    cells = metric_cells(columns)
    groups = [(key, metric_block(_stat_matrix(g, len(columns)), cells)) for key, g in _groups(sums, by)]
    cols = [*by, "target", "strategy", "fraction", "metric", "estimate", "ci_low", "ci_high", "ece_plugin"]
    return block_frame(cells.keys, list(by), groups).reindex(columns=[*cols, "n_episodes"])


def paired_differences(sums: pd.DataFrame, columns: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """Differences between strategies on the same episodes, with paired bootstrap intervals.

    Returns
    -------
    tidy DataFrame: the columns of ``by``, target, fraction, metric, strategy, baseline, difference
    (strategy − baseline; for the ECE bias-corrected), ci_low, ci_high, p_value (two-sided bootstrap,
    unadjusted), better (the interval excludes 0 on the side where the metric improves), verdict
    (``better``, ``worse`` or ``no difference``: :func:`verdict`, unadjusted), for every pair of strategies
    predicting the same target (strategy after baseline in the settings' order)
    """
    cells = metric_cells(columns)
    pairs = difference_pairs(cells)
    groups = [
        (key, difference_block(_stat_matrix(g, len(columns)), cells, pairs)) for key, g in _groups(sums, by)
    ]
    cols = [*by, "target", "fraction", "metric", "strategy", "baseline", "difference", "ci_low", "ci_high"]
    return block_frame(pairs.keys, list(by), groups).reindex(columns=[*cols, "p_value", "better", "verdict"])


def reliability_block(s0: np.ndarray, columns: pd.DataFrame | dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """One group's reliability diagrams from its plain sums ``s0`` (shape (K,)): n, confidence, accuracy per
    (target, strategy, fraction, bin) of :func:`reliability_keys` (``columns``: the statistics' description,
    or its :func:`reliability_index`)."""
    idx = columns if isinstance(columns, dict) else reliability_index(columns)
    cnt = s0[idx["bin_n"]]
    with np.errstate(invalid="ignore", divide="ignore"):
        conf, right = s0[idx["bin_confidence"]] / cnt, s0[idx["bin_correct"]] / cnt
    return {"n": cnt, "confidence": conf, "accuracy": right}


def reliability_index(columns: pd.DataFrame) -> dict[str, np.ndarray]:
    """Where each bin statistic sits among the statistics (for :func:`reliability_block`): ``bin_n``,
    ``bin_confidence``, ``bin_correct`` → int array, shape (n_rows,), its position in a row of sums for each
    (target, strategy, fraction, bin)."""
    binned = columns[columns["bin"] >= 0]
    return {
        st: binned.index[binned.stat == st].to_numpy() for st in ("bin_n", "bin_confidence", "bin_correct")
    }


def reliability_keys(columns: pd.DataFrame) -> pd.DataFrame:
    """The rows of a reliability diagram: target, strategy, fraction, bin, lower, upper."""
    binned = columns[columns["bin"] >= 0]
    base = binned[binned.stat == "bin_n"][["target", "strategy", "fraction", "bin"]].reset_index(drop=True)
    n_bins = int(binned["bin"].max()) + 1 if len(binned) else 1
    base["lower"], base["upper"] = base["bin"] / n_bins, (base["bin"] + 1) / n_bins
    return base


def reliability(sums: pd.DataFrame, columns: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """The reliability diagrams of the calibration bins (the estimate, row 0 of the sums).

    Returns
    -------
    tidy DataFrame: the columns of ``by``, target, strategy, fraction, bin, lower, upper (the bin's
    confidence range), n (episodes in the bin), confidence (their mean top-label confidence), accuracy
    (how often that label was right)
    """
    cols = [*by, "target", "strategy", "fraction", "bin", "lower", "upper", "n", "confidence", "accuracy"]
    if columns[columns["bin"] >= 0].empty:
        return pd.DataFrame(columns=cols)
    keys = reliability_keys(columns)
    groups = [
        (key, reliability_block(_stat_matrix(g, len(columns))[0], columns)) for key, g in _groups(sums, by)
    ]
    return block_frame(keys, list(by), groups).reindex(columns=cols)


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
