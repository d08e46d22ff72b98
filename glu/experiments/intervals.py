"""Bootstrap intervals that stream: sums with Poisson weights, merged across chunks, turned into metrics.

A corpus of a million episodes cannot be resampled as a whole, so glu uses the **Poisson bootstrap**
(Hanley & MacGibbon 2006; Chamandy et al. 2012, "Estimating uncertainty for massive data streams"): each
episode gets, for each replicate ``b = 1 … B``, an independent weight ``w_b ~ Poisson(1)`` — the number of
times an ordinary bootstrap would draw it, in the limit of a large sample. A chunk only keeps the
weighted sums of its per-episode statistics, ``S_b = Σ_e w_{e,b} x_e`` (row 0: all weights 1, the
plain sums), chunks add up, and every metric of replicate b is computed from ``S_b`` exactly as the
estimate is from ``S_0``:

* a mean (accuracy, log-loss, Brier, description correctness) is ``S_b[stat] / S_b[n]``;
* the expected calibration error (top label, equal-width bins) is ``Σ_bins |S_b[correct_bin] −
  S_b[confidence_bin]| / S_b[n]``.

The 95 % interval is the 2.5th to 97.5th percentile of the replicates (percentile bootstrap). The ECE is
biased upwards by sampling noise, its replicates more so: for a well-calibrated predictor the interval can
sit mostly above the estimate. Because the
weights belong to episodes (the same for every strategy, fraction and condition of an episode), the
difference of two strategies is resampled *paired*: :func:`paired_differences` takes the percentiles of
the replicates' differences.

:func:`metrics`, :func:`paired_differences` and :func:`reliability` turn merged sums (one row per
condition and replicate) into tidy tables.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from glu.errors import DataError

BOOT_KEY = 2
"""Spawn key of a chunk's bootstrap weights."""
LEVEL = 0.95
"""Interval coverage."""
MEAN_METRICS: dict[str, str] = {"correct": "accuracy", "log_loss": "log_loss", "brier": "brier"}
"""Per-episode statistic → the metric that is its mean."""
HIGHER_IS_BETTER: dict[str, bool] = {
    "accuracy": True, "log_loss": False, "brier": False, "ece": False,
    "verb": True, "object": True, "effect": True, "all": True,
}  # fmt: skip


def poisson_weights(n: int, replicates: int, rng: np.random.Generator) -> np.ndarray:
    """Bootstrap weights of ``n`` episodes, shape (n, replicates + 1): column 0 all ones, then Poisson(1)."""
    w = np.empty((n, replicates + 1))
    w[:, 0] = 1.0
    w[:, 1:] = rng.poisson(1.0, size=(n, replicates))
    return w


def accumulate(blocks: Sequence[np.ndarray], weights: np.ndarray) -> np.ndarray:
    """Weighted sums ``Wᵀ X`` of per-episode statistics given as column blocks, shape (B + 1, K)."""
    return np.concatenate([weights.T @ np.asarray(b, dtype=float) for b in blocks], axis=1)


def _interval(reps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Percentile interval over axis 0 (NaN without replicates)."""
    if len(reps) == 0:
        nan = np.full(reps.shape[1:], np.nan)
        return nan, nan
    lo, hi = np.nanpercentile(reps, [50 * (1 - LEVEL), 50 * (1 + LEVEL)], axis=0)
    return lo, hi


def metric_values(sums: np.ndarray, columns: pd.DataFrame) -> pd.DataFrame:
    """Every metric of every replicate: a frame with one column per metric cell, one row per replicate.

    Parameters
    ----------
    sums : array, shape (B + 1, K) — merged sums (row 0 the estimate)
    columns : the statistics' description (:func:`glu.experiments.evaluation.statistic_columns`)

    Returns
    -------
    DataFrame, shape (B + 1, n_cells), columns a MultiIndex (target, strategy, fraction, metric)
    """
    if sums.shape[1] != len(columns):
        raise DataError(
            f"{sums.shape[1]} sums for {len(columns)} statistics: the chunks do not match the settings"
        )
    n = sums[:, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        out = {}
        cells = columns.iloc[1:]
        plain = cells[cells["bin"] < 0]
        for k, row in plain.iterrows():
            metric = MEAN_METRICS.get(row.stat, row.stat)
            out[(row.target, row.strategy, row.fraction, metric)] = sums[:, k] / n
        binned = cells[cells["bin"] >= 0]
        for (target, strategy, fraction), g in binned.groupby(["target", "strategy", "fraction"], sort=False):
            conf = sums[:, g.index[g.stat == "bin_confidence"]]
            corr = sums[:, g.index[g.stat == "bin_correct"]]
            out[(target, strategy, fraction, "ece")] = np.abs(corr - conf).sum(axis=1) / n
    frame = pd.DataFrame(out)
    frame.columns = pd.MultiIndex.from_tuples(
        frame.columns, names=["target", "strategy", "fraction", "metric"]
    )
    return frame


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
    tidy DataFrame: *by, target, strategy, fraction, metric, estimate, ci_low, ci_high, n_episodes
    """
    rows = []
    for key, g in _groups(sums, by):
        vals = metric_values(_stat_matrix(g, len(columns)), columns)
        lo, hi = _interval(vals.to_numpy()[1:])
        n = float(_stat_matrix(g, len(columns))[0, 0])
        for j, cell in enumerate(vals.columns):
            rows.append((*key, *cell, vals.iat[0, j], lo[j], hi[j], n))
    return pd.DataFrame(
        rows,
        columns=[
            *by,
            "target",
            "strategy",
            "fraction",
            "metric",
            "estimate",
            "ci_low",
            "ci_high",
            "n_episodes",
        ],
    )


def paired_differences(sums: pd.DataFrame, columns: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """Differences between strategies on the same episodes, with paired bootstrap intervals.

    Returns
    -------
    tidy DataFrame: *by, target, fraction, metric, strategy, baseline, difference (strategy − baseline),
    ci_low, ci_high, better (the interval excludes 0 on the side where the metric improves), for every
    pair of strategies predicting the same target (strategy after baseline in the settings' order)
    """
    rows = []
    for key, g in _groups(sums, by):
        vals = metric_values(_stat_matrix(g, len(columns)), columns)
        for (target, fraction, metric), cells in vals.T.groupby(
            level=["target", "fraction", "metric"], sort=False
        ):
            strategies = [c[1] for c in cells.index]
            for i, base in enumerate(strategies):
                for strat in strategies[i + 1 :]:
                    d = (
                        cells.loc[(target, strat, fraction, metric)].to_numpy()
                        - cells.loc[(target, base, fraction, metric)].to_numpy()
                    )
                    lo, hi = _interval(d[1:, None])
                    up = HIGHER_IS_BETTER.get(metric, True)
                    better = bool(lo[0] > 0) if up else bool(hi[0] < 0)
                    rows.append((*key, target, fraction, metric, strat, base, d[0], lo[0], hi[0], better))
    return pd.DataFrame(
        rows,
        columns=[
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
        ],
    )


def reliability(sums: pd.DataFrame, columns: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """The reliability diagram of the effect's calibration bins (the estimate, row 0 of the sums).

    Returns
    -------
    tidy DataFrame: *by, strategy, fraction, bin, lower, upper (the bin's confidence range), n (episodes
    in the bin), confidence (their mean top-label confidence), accuracy (how often that label was right)
    """
    rows = []
    binned = columns[columns["bin"] >= 0]
    if binned.empty:
        return pd.DataFrame(
            columns=[*by, "strategy", "fraction", "bin", "lower", "upper", "n", "confidence", "accuracy"]
        )
    n_bins = int(binned["bin"].max()) + 1
    for key, g in _groups(sums, by):
        s0 = _stat_matrix(g, len(columns))[0]
        for (strategy, fraction), cells in binned.groupby(["strategy", "fraction"], sort=False):
            for b in range(n_bins):
                at = cells[cells["bin"] == b]
                cnt, conf, corr = (
                    s0[at.index[at.stat == st][0]] for st in ("bin_n", "bin_confidence", "bin_correct")
                )
                with np.errstate(invalid="ignore", divide="ignore"):
                    rows.append(
                        (
                            *key,
                            strategy,
                            fraction,
                            b,
                            b / n_bins,
                            (b + 1) / n_bins,
                            cnt,
                            conf / cnt,
                            corr / cnt,
                        )
                    )
    return pd.DataFrame(
        rows, columns=[*by, "strategy", "fraction", "bin", "lower", "upper", "n", "confidence", "accuracy"]
    )


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
