"""Intervals: bootstrap replicates at two levels (training seeds, then items within each), the percentile
interval, the exact interval of a proportion, and the verdict on a difference.

Two resampling schemes share this module, both nested (Davison & Hinkley 1997, §3.8, the two-stage bootstrap):
each replicate draws the training seeds with replacement, then the items (test gestures, episodes) of each
drawn seed.

* **Poisson weights**, for statistics that stream (Hanley & MacGibbon 2006; Chamandy et al. 2012): each item
  gets, for each replicate ``b = 1 … B``, an independent weight ``w_b ~ Poisson(c_{b,k})``, where ``c_{b,k}``
  is how often its seed ``k`` was drawn (:func:`seed_counts`, :func:`poisson_weights`). A chunk keeps only
  the weighted sums ``S_b = Σ_e w_{e,b} x_e`` (row 0: all weights 1, the plain sums), chunks add up
  (:func:`accumulate`), and every metric of replicate ``b`` is computed from ``S_b`` as the estimate is from
  ``S_0``. With one seed this is the one-level Poisson bootstrap. :func:`two_level_sums` does the same for
  statistics held in memory. The corpus evaluation (:mod:`glu.studies.corpus_evaluation.intervals`) and the
  correspondence study use it.
* **Multinomial weights**, for values held per (seed, item) (:func:`two_level_weights`,
  :func:`replicate_means`): each drawn seed adds a multinomial draw of its items. Learning from effects uses
  it.

The interval is the 2.5th to 97.5th percentile of the replicates (:data:`LEVEL`, :func:`percentile_interval`,
:func:`interval`). Because the weights belong to items, the same for every method measured on them, the
difference of two methods is resampled *paired*, and a difference whose interval contains 0 is no difference
(:func:`verdict`). :func:`clopper_pearson` gives the exact interval of a single proportion (k of n).

**Many verdicts at once.** A study that reads many differences (every condition, cell and feature set)
adjusts for their number. :func:`bootstrap_p_value` gives the two-sided p-value of a difference from its
replicates (consistent with the percentile interval: p < 0.05 exactly when fewer than 2.5 % of the
replicates fall on the far side of 0, up to one replicate); :func:`holm` (Holm 1979, the family-wise error)
and :func:`benjamini_hochberg` (Benjamini & Hochberg 1995, the false discovery rate) adjust a family of
p-values; :func:`adjusted_verdict` reads a verdict from an adjusted p-value. With ``B`` replicates the
smallest bootstrap p-value is ``2 / (B + 1)``, so Holm's first threshold ``α / m`` is out of reach for a
family of ``m > α (B + 1) / 2`` differences whatever the data (25 at B = 1,000): such families are adjusted
by Benjamini–Hochberg, which rejects the ``k`` smallest when ``p_(k) ≤ k α / m``.

**Equivalence.** That an interval contains 0 says that no difference was found, not that there is none.
"A matches B" is claimed only by an equivalence test against a margin ``m`` declared beforehand: the two
one-sided tests (TOST; Schuirmann 1987) of ``H0: δ ≤ −m`` and ``H0: δ ≥ m``, each at level α.
:func:`tost_p_value` reads them from the bootstrap replicates of the difference (``p = max(p_−, p_+)``,
each one-sided p-value counted as :func:`bootstrap_p_value` counts; equivalence at α exactly when the
``1 − 2α`` percentile interval lies inside ``(−m, m)``, up to one replicate), and
:func:`equivalence_verdict` says ``"equivalent"`` or not from a (possibly adjusted) p-value.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np

from glu.errors import DataError

LEVEL = 0.95
"""Interval coverage."""
HIGHER_IS_BETTER: dict[str, bool] = {
    "accuracy": True,
    "log_loss": False,
    "brier": False,
    "ece": False,
    "verb": True,
    "object": True,
    "effect": True,
    "all": True,
}
"""Whether a larger value of each metric is better (the sign of a verdict)."""


def seed_counts(n_seeds: int, replicates: int, rng: np.random.Generator) -> np.ndarray:
    """How often each of ``n_seeds`` seeds is drawn in each replicate, shape (replicates + 1, n_seeds).

    Row 0 is all ones (the estimate uses every seed once); rows 1 … are multinomial(n_seeds, uniform): a
    resample of the seeds with replacement.
    """
    if n_seeds < 1:
        raise DataError(f"a bootstrap over seeds needs at least one seed, not {n_seeds}")
    out = np.ones((replicates + 1, n_seeds), dtype=np.int64)
    if replicates:
        out[1:] = rng.multinomial(n_seeds, np.full(n_seeds, 1.0 / n_seeds), size=replicates)
    return out


def poisson_weights(
    n: int, replicates: int, rng: np.random.Generator, counts: np.ndarray | None = None
) -> np.ndarray:
    """Bootstrap weights of ``n`` episodes, shape (n, replicates + 1): column 0 all ones, then Poisson.

    Parameters
    ----------
    n, replicates : episodes and bootstrap replicates
    rng : the generator of the weights
    counts : array, shape (replicates + 1,) — for a two-level bootstrap, how often the episodes' seed is
        drawn in each replicate (a column of :func:`seed_counts`); replicate b's weights are then
        Poisson(``counts[b]``). Default: all ones (one level, Poisson(1)).
    """
    w = np.empty((n, replicates + 1))
    w[:, 0] = 1.0
    if counts is None:
        w[:, 1:] = rng.poisson(1.0, size=(n, replicates))
    else:
        counts = np.asarray(counts, dtype=float)
        if counts.shape != (replicates + 1,):
            raise DataError(f"counts of shape {counts.shape}; expected ({replicates + 1},)")
        w[:, 1:] = rng.poisson(counts[1:], size=(n, replicates))
    return w


def two_level_sums(stats: Sequence[np.ndarray], replicates: int, rng: np.random.Generator) -> np.ndarray:
    """Two-level bootstrap sums of per-item statistics held in memory, shape (replicates + 1, S).

    Row 0 is the plain sum over every seed and item; row b weighs seed k's items by Poisson(``c_{b,k}``)
    (see the module docstring).

    Parameters
    ----------
    stats : one array per seed, shape (n_k, S) — the statistics of each of its items (test gestures,
        episodes); column 0 is usually 1 (the count)
    replicates : bootstrap replicates
    rng : the generator (the seed counts first, then each seed's weights in turn)
    """
    counts = seed_counts(len(stats), replicates, rng)
    width = {np.asarray(x).shape[1] for x in stats}
    if len(width) != 1:
        raise DataError("two_level_sums: every seed needs the same statistics (columns)")
    total = np.zeros((replicates + 1, width.pop()))
    for k, x in enumerate(stats):
        x = np.asarray(x, dtype=float)
        total += poisson_weights(len(x), replicates, rng, counts[:, k]).T @ x
    return total


def clopper_pearson(k: int, n: int, level: float = LEVEL) -> tuple[float, float]:
    """The exact (Clopper–Pearson) two-sided interval of a proportion of ``k`` successes in ``n`` trials."""
    from scipy import stats

    if not (0 <= k <= n) or n < 1:
        raise DataError(f"clopper_pearson: need 0 ≤ k ≤ n and n ≥ 1, not k={k}, n={n}")
    a = (1 - level) / 2
    lo = 0.0 if k == 0 else float(stats.beta.ppf(a, k, n - k + 1))
    hi = 1.0 if k == n else float(stats.beta.ppf(1 - a, k + 1, n - k))
    return lo, hi


def verdict(low: float, high: float, higher_is_better: bool = True) -> str:
    """``"better"``, ``"worse"`` or ``"no difference"`` for the interval of a difference (A − B)."""
    if not (np.isfinite(low) and np.isfinite(high)):
        return "no difference"
    if low > 0:
        return "better" if higher_is_better else "worse"
    if high < 0:
        return "worse" if higher_is_better else "better"
    return "no difference"


def accumulate(blocks: Sequence[np.ndarray], weights: np.ndarray) -> np.ndarray:
    """Weighted sums ``Wᵀ X`` of per-episode statistics given as column blocks, shape (B + 1, K)."""
    return np.concatenate([weights.T @ np.asarray(b, dtype=float) for b in blocks], axis=1)


def percentile_interval(reps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Percentile interval over axis 0 (NaN without replicates).

    ``reps``, shape (B, ...) — the replicates only (the estimate's row already dropped); returns ``(low,
    high)``, each of shape ``reps.shape[1:]``, in the replicates' units.
    """
    if len(reps) == 0:
        nan = np.full(reps.shape[1:], np.nan)
        return nan, nan
    q = [50 * (1 - LEVEL), 50 * (1 + LEVEL)]
    nan = np.isnan(reps).any(axis=0)
    lo, hi = np.percentile(np.where(nan, 0.0, reps), q, axis=0)  # NaN-free columns, fast
    if nan.any():  # a metric undefined in some replicates (e.g. no episode in a group): skip those
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            lo[nan], hi[nan] = np.nanpercentile(reps[:, nan], q, axis=0)
    return lo, hi


def two_level_weights(n_seeds: int, n_units: int, replicates: int, rng: np.random.Generator) -> np.ndarray:
    """Bootstrap weights of every (seed, unit), shape (replicates + 1, n_seeds, n_units); row 0 all ones.

    Replicate ``b``: ``n_seeds`` seeds drawn with replacement; each drawn seed adds a multinomial draw of
    ``n_units`` of its units (each with probability ``1 / n_units``) to its row.
    """
    if n_seeds < 1 or n_units < 1:
        raise DataError(f"a two-level bootstrap needs seeds and units, got {n_seeds} and {n_units}")
    W = np.zeros((replicates + 1, n_seeds, n_units))
    W[0] = 1.0
    for b in range(1, replicates + 1):
        for s in rng.integers(0, n_seeds, size=n_seeds):
            W[b, s] += rng.multinomial(n_units, np.full(n_units, 1.0 / n_units))
    return W


def replicate_means(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted means of per-(seed, unit) values, shape (S, J, ...), for each replicate: (B + 1, ...);
    row 0 is the plain mean over every seed and unit."""
    values = np.asarray(values, dtype=float)
    S, J = values.shape[:2]
    flat = values.reshape(S * J, -1)
    w = weights.reshape(len(weights), S * J)
    return ((w @ flat) / w.sum(axis=1, keepdims=True)).reshape((len(weights),) + values.shape[2:])


def interval(replicates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The percentile interval of :data:`LEVEL` over axis 0 of replicate estimates (row 0 excluded).

    ``replicates``, shape (B + 1, ...) — row 0 the estimate, rows 1 … the replicates; returns ``(low, high)``,
    each of shape ``replicates.shape[1:]`` (NaN when B = 0).
    """
    reps = np.asarray(replicates, dtype=float)[1:]
    if len(reps) == 0:
        nan = np.full(np.shape(replicates)[1:], np.nan)
        return nan, nan
    lo, hi = np.percentile(reps, [50 * (1 - LEVEL), 50 * (1 + LEVEL)], axis=0)
    return lo, hi


ALPHA = 1 - LEVEL
"""The error rate of a verdict (two-sided), before and after adjustment."""


def bootstrap_p_value(replicates: np.ndarray, null: float = 0.0) -> np.ndarray:
    """Two-sided bootstrap p-values of differences from their replicates (row 0, the estimate, excluded).

    ``p = min(1, 2 · (1 + min(#{d* ≤ null}, #{d* ≥ null})) / (B + 1))`` over the ``B`` replicates ``d*`` of
    each column (Davison & Hinkley 1997, §4.4; the +1 counts the estimate itself, so p is never 0). A
    column with NaN replicates uses its finite ones; none: NaN.

    Parameters
    ----------
    replicates : array, shape (B + 1, ...) — row 0 the estimate, rows 1 … the replicates
    null : the value of the difference under the null hypothesis
    """
    reps = np.asarray(replicates, dtype=float)[1:]
    finite = np.isfinite(reps)
    b = finite.sum(axis=0)
    below = (finite & (reps <= null)).sum(axis=0)
    above = (finite & (reps >= null)).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = np.minimum(1.0, 2.0 * (1 + np.minimum(below, above)) / (b + 1))
    return np.where(b > 0, p, np.nan)


def _family(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p = np.asarray(p, dtype=float)
    ok = np.isfinite(p)
    if ((p[ok] < 0) | (p[ok] > 1)).any():
        raise DataError("p-values must lie in [0, 1]")
    return p, ok, p[ok]


def holm(p: np.ndarray) -> np.ndarray:
    """Holm's step-down adjusted p-values of a family (NaN entries are not in the family and stay NaN).

    ``p̃_(i) = max_{j ≤ i} min(1, (m − j + 1) p_(j))`` for the sorted p-values ``p_(1) ≤ … ≤ p_(m)``:
    rejecting ``p̃ ≤ α`` keeps the family-wise error rate at α under any dependence. ``p``: array of any
    shape, usually (m,); the adjusted p-values have the same shape.
    """
    p, ok, q = _family(p)
    out = np.full(p.shape, np.nan)
    m = len(q)
    if m:
        order = np.argsort(q, kind="stable")
        adj = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * q[order]))
        res = np.empty(m)
        res[order] = adj
        out[ok] = res
    return out


def benjamini_hochberg(p: np.ndarray) -> np.ndarray:
    """Benjamini–Hochberg step-up adjusted p-values (q-values) of a family (NaN entries stay NaN).

    ``p̃_(i) = min_{j ≥ i} min(1, m p_(j) / j)``: rejecting ``p̃ ≤ α`` keeps the expected share of false
    verdicts among those reported at α (for independent or positively dependent tests). ``p``: array of any
    shape, usually (m,); the adjusted p-values have the same shape.
    """
    p, ok, q = _family(p)
    out = np.full(p.shape, np.nan)
    m = len(q)
    if m:
        order = np.argsort(q, kind="stable")
        scaled = q[order] * m / np.arange(1, m + 1)
        adj = np.minimum(1.0, np.minimum.accumulate(scaled[::-1])[::-1])
        res = np.empty(m)
        res[order] = adj
        out[ok] = res
    return out


ADJUSTMENTS = {"holm": holm, "bh": benjamini_hochberg}
"""The multiplicity adjustments by name."""


def adjust(p: np.ndarray, method: str = "bh") -> np.ndarray:
    """The adjusted p-values of a family by ``method`` (:data:`ADJUSTMENTS`), of the same shape as ``p``."""
    if method not in ADJUSTMENTS:
        raise DataError(f"unknown adjustment {method!r}; allowed: {', '.join(ADJUSTMENTS)}")
    return ADJUSTMENTS[method](p)


def adjusted_verdict(estimate: float, p_adjusted: float, higher_is_better: bool = True) -> str:
    """``"better"``, ``"worse"`` or ``"no difference"`` for a difference (A − B) whose adjusted p-value
    is ``p_adjusted``: a verdict only when ``p_adjusted ≤`` :data:`ALPHA`, in the direction of the
    estimate."""
    if not (np.isfinite(estimate) and np.isfinite(p_adjusted)) or p_adjusted > ALPHA or estimate == 0:
        return "no difference"
    return "better" if (estimate > 0) == higher_is_better else "worse"


def tost_p_value(replicates: np.ndarray, margin: float) -> np.ndarray:
    """Bootstrap p-values of the two one-sided tests of equivalence (TOST) within ``± margin``.

    ``p = max(p_−, p_+)`` with ``p_− = (1 + #{d* ≤ −m}) / (B + 1)`` (the null ``δ ≤ −m``) and ``p_+ = (1 +
    #{d* ≥ m}) / (B + 1)`` (the null ``δ ≥ m``) over the ``B`` finite replicates ``d*`` of each column (row 0,
    the estimate, excluded). A small p says the difference lies inside the margin; rejecting at α is the
    ``1 − 2α`` percentile interval lying inside ``(−m, m)``. A column without finite replicates: NaN.

    Parameters
    ----------
    replicates : array, shape (B + 1, ...) — row 0 the estimate, rows 1 … the replicates of a difference
    margin : the equivalence margin ``m > 0``, in the difference's units, declared before the data are seen

    >>> reps = np.array([0.0, -0.03, -0.01, 0.0, 0.01, 0.015])
    >>> float(tost_p_value(reps, 0.02))  # one replicate of five at or below −0.02, none at or above 0.02
    0.3333333333333333
    """
    if not (isinstance(margin, int | float) and 0 < margin < math.inf):
        raise DataError(f"margin={margin!r}: the equivalence margin must be a number > 0")
    reps = np.asarray(replicates, dtype=float)[1:]
    finite = np.isfinite(reps)
    b = finite.sum(axis=0)
    low = (finite & (reps <= -margin)).sum(axis=0)
    high = (finite & (reps >= margin)).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = (1.0 + np.maximum(low, high)) / (b + 1)
    return np.where(b > 0, np.minimum(p, 1.0), np.nan)


def equivalence_verdict(p_tost: float, alpha: float = ALPHA) -> bool:
    """Whether a TOST p-value (:func:`tost_p_value`, adjusted or not) establishes equivalence at ``alpha``."""
    return bool(np.isfinite(p_tost) and p_tost <= alpha)
