"""Two-level bootstrap intervals: training runs (seeds) and, within each, the held-out episodes it was
measured on.

A learning curve's accuracy varies for two reasons: the training run (which episodes the robot happened to
see, how EM started) and the finite set of held-out gestures it was measured on. One run's test set says
nothing about the first, so the resampling is nested (Davison & Hinkley 1997, §3.8, the two-stage
bootstrap): each replicate draws the seeds with replacement, then, within each drawn seed, its held-out
episodes with replacement (multinomial counts), and averages the per-episode values with those counts as
weights. The interval is the 2.5th to 97.5th percentile of the replicates (:data:`LEVEL`).

The same weights serve every cell (learner, condition, number of episodes) of a seed, so the difference of
two learners measured on the same seeds and episodes is resampled *paired*: the percentiles of the
replicates' differences.

(A two-level bootstrap for other studies may live in :mod:`glu.experiments.intervals`; this one is kept
small and separate on purpose.)
"""

from __future__ import annotations

import numpy as np

from glu.errors import DataError
from glu.experiments.intervals import LEVEL


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
    """The percentile interval of :data:`LEVEL` over axis 0 of replicate estimates (row 0 excluded)."""
    reps = np.asarray(replicates, dtype=float)[1:]
    if len(reps) == 0:
        nan = np.full(np.shape(replicates)[1:], np.nan)
        return nan, nan
    lo, hi = np.percentile(reps, [50 * (1 - LEVEL), 50 * (1 + LEVEL)], axis=0)
    return lo, hi
