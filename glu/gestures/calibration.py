"""Reading ``p_HMM(A | G)`` from the HMMs' log-likelihoods: as the originals, per frame, or calibrated.

A recogniser gives ``ℓ_a = log L(G_1^t | A = a)`` for each action. The posterior with equal priors is a
softmax of the log-likelihoods times an inverse temperature ``β``: ``p_HMM(a | G) ∝ exp(β ℓ_a)``. The
three readings of :data:`READINGS` differ only in ``β``:

``likelihood``
    ``β = 1``, the originals' ``L(G | a) / Σ_h L(G | h)``. A likelihood multiplies t frame densities as
    if the frames were independent given the states, so p_HMM is nearly certain after a few dozen frames,
    right or wrong.
``per-frame``
    ``β = 1 / t``: the per-frame log-likelihood TCDS plots, tempered by the number of frames seen.
``calibrated``
    ``β`` fitted by temperature scaling (Guo et al. 2017, "On calibration of modern neural networks"):
    the ``β ∈ [0, 1]`` that minimises the log-loss ``−Σ_i log p_β(y_i | G_i)`` on **held-out training
    gestures** (gestures of the training distribution that the models were not trained on; never the test
    episodes), one ``β`` per observed fraction of the gesture (:func:`fit_calibration`). The log-loss is
    convex in ``β`` (a log-sum-exp of functions linear in β, minus a linear term), so a bounded scalar
    search finds the minimum; ``β ≤ 1`` keeps the calibrated reading between "no information"
    (``β = 0``) and the likelihood reading.

Example
-------
>>> import numpy as np
>>> ll = np.array([[-100.0, -130.0, -160.0]])
>>> p_hmm_reading(ll, np.array([30]), "likelihood").round(3), p_hmm_reading(ll, np.array([30]),
...                                                                     "per-frame").round(3)
(array([[1., 0., 0.]]), array([[0.665, 0.245, 0.09 ]]))
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from glu.errors import DataError

READINGS: dict[str, str] = {
    "likelihood": "p_HMM(A | G_1^t) ∝ L(G_1^t | A), equal priors (the originals')",
    "per-frame": "p_HMM(A | G_1^t) ∝ exp((1/t) log L(G_1^t | A)), the per-frame log-likelihood TCDS plots",
    "calibrated": "p_HMM(A | G_1^t) ∝ exp(β log L(G_1^t | A)), β fitted on held-out training gestures",
}
"""How the robot turns its HMMs' log-likelihoods into ``p_HMM``."""
BETA_BOUNDS = (0.0, 1.0)
"""The range searched for the calibrated inverse temperature."""


def softmax_rows(scores: np.ndarray) -> np.ndarray:
    """``exp(s) / Σ exp(s)`` along the last axis, computed stably; rows with no finite score become
    uniform. ``scores``, shape (..., K) (e.g. scaled log-likelihoods) → probabilities, shape (..., K)."""
    s = np.asarray(scores, dtype=float)
    top = np.max(np.where(np.isfinite(s), s, -np.inf), axis=-1, keepdims=True)
    ok = np.isfinite(top)
    with np.errstate(invalid="ignore", over="ignore"):
        e = np.exp(np.where(ok, s - np.where(ok, top, 0.0), -np.inf))
        p = e / e.sum(axis=-1, keepdims=True)
    p[~np.isfinite(p).all(axis=-1)] = 1.0 / s.shape[-1]
    return p


def p_hmm_reading(
    loglik: np.ndarray, frames: np.ndarray, reading: str, beta: float | np.ndarray | None = None
) -> np.ndarray:
    """``p_HMM`` from log-likelihoods, shape (..., K) → (..., K).

    Parameters
    ----------
    loglik : array, shape (..., K) — ``log L(G_1^t | a)`` per action
    frames : array, shape (...) — t, the frames seen (used by ``per-frame``)
    reading : a name of :data:`READINGS`
    beta : the calibrated inverse temperature(s), broadcast against ``frames`` (``calibrated`` only)
    """
    ll = np.asarray(loglik, dtype=float)
    if reading == "likelihood":
        b = 1.0
    elif reading == "per-frame":
        b = 1.0 / np.maximum(np.asarray(frames, dtype=float), 1.0)[..., None]
    elif reading == "calibrated":
        if beta is None:
            raise DataError("the calibrated reading of p_HMM needs its fitted β (fit_calibration)")
        b = np.asarray(beta, dtype=float)[..., None] if np.ndim(beta) else float(beta)
    else:
        raise DataError(f"unknown reading of p_HMM {reading!r}; allowed: {', '.join(READINGS)}")
    with np.errstate(invalid="ignore"):
        scaled = np.where(np.isfinite(ll), b * ll, -np.inf)
    return softmax_rows(scaled)


def log_loss_at(beta: float, loglik: np.ndarray, labels: np.ndarray) -> float:
    """Mean ``−log p_β(y | G)`` of softmax(β ℓ), shape (n, K) with labels (n,) (``β = 0``: log K)."""
    s = beta * loglik
    top = s.max(axis=1, keepdims=True)
    lse = top[:, 0] + np.log(np.exp(s - top).sum(axis=1))
    return float(np.mean(lse - s[np.arange(len(s)), labels]))


def fit_temperature(loglik: np.ndarray, labels: np.ndarray) -> float:
    """The inverse temperature ``β ∈ [0, 1]`` minimising the log-loss of softmax(β ℓ) on labelled gestures.

    Parameters
    ----------
    loglik : array, shape (n, K) — log-likelihoods of n held-out gestures under each action's model
    labels : int array, shape (n,) — their actions (indices into K)

    Rows with a non-finite log-likelihood are left out (a model that finds a gesture impossible).
    """
    from scipy.optimize import minimize_scalar

    ll = np.asarray(loglik, dtype=float)
    y = np.asarray(labels, dtype=np.intp)
    if ll.ndim != 2 or y.shape != (len(ll),) or (y < 0).any() or (y >= ll.shape[1]).any():
        raise DataError(
            f"fit_temperature: log-likelihoods (n, K) and labels (n,) in 0…K−1; got {ll.shape}, {y.shape}"
        )
    keep = np.isfinite(ll).all(axis=1)
    ll, y = ll[keep], y[keep]
    if len(ll) == 0:
        raise DataError("fit_temperature: no held-out gesture with finite log-likelihoods")
    ll = ll - ll.max(axis=1, keepdims=True)  # the softmax is unchanged; the numbers stay small
    lo, hi = BETA_BOUNDS
    res = minimize_scalar(
        log_loss_at, bounds=(lo, hi), args=(ll, y), method="bounded", options={"xatol": 1e-7}
    )
    best = float(res.x)
    for edge in (lo, hi):  # the bounded search never evaluates the ends themselves
        if log_loss_at(edge, ll, y) <= log_loss_at(best, ll, y):
            best = edge
    return best


class Calibration(NamedTuple):
    """The calibrated reading's inverse temperature at each observed fraction of a gesture.

    Attributes
    ----------
    fractions : array, shape (F,) — observed fractions
    beta : array, shape (F,) — the fitted β at each
    n_gestures : how many held-out gestures they were fitted on
    """

    fractions: np.ndarray
    beta: np.ndarray
    n_gestures: int

    def at(self, fraction: float) -> float:
        """β at one of the fitted fractions."""
        i = np.flatnonzero(np.isclose(self.fractions, fraction))
        if len(i) != 1:
            raise DataError(f"no calibration at fraction {fraction}; fitted at {self.fractions.tolist()}")
        return float(self.beta[i[0]])


def fit_calibration(loglik: np.ndarray, labels: np.ndarray, fractions: Sequence[float]) -> Calibration:
    """One β per fraction from held-out gestures' log-likelihoods, shape (n, F, K), labels (n,)."""
    ll = np.asarray(loglik, dtype=float)
    if ll.ndim != 3 or ll.shape[1] != len(fractions):
        raise DataError(f"fit_calibration: log-likelihoods of shape (n, {len(fractions)}, K), not {ll.shape}")
    beta = np.array([fit_temperature(ll[:, j], labels) for j in range(len(fractions))])
    return Calibration(np.asarray(fractions, dtype=float), beta, len(ll))
