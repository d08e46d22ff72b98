"""Baum–Welch for GMM-HMMs with full covariances and weighted sequences: the readable reference.

This module is the reference of EM in pure NumPy, the one to read and edit first and the oracle of the
tests; the fast implementation that every trainer runs, many models at once, is
:func:`glu.hmm._engine.em_batch.fit_many` (equal to this to rounding, tested). EM here is written from
its sufficient statistics, with a weight per sequence (a sequence labelled ``a`` with probability ``p``
counts ``p`` times in ``a``'s model; unweighted EM is every weight 1):

* :func:`expected_stats` — the E-step: :class:`SufficientStats` (expected state, transition and component
  counts, first and second moments of the frames), each sequence's contribution times its weight; the
  sequences are padded to a common length and pass through one forward and one backward recursion
  together (:func:`glu.hmm.inference.forward_backward`). Statistics of disjoint sets of sequences add up
  (``a + b``), so they can be accumulated episode by episode (online learning, :mod:`glu.hmm.online`);
* :func:`maximise` — the M-step from statistics (any leading batch axes: many models at once);
* :func:`fit` — the two in a loop until the weighted log-likelihood ``Σ_s w_s log L(G_s)`` converges.

The M-step re-estimates every parameter with flat Dirichlet priors on the initial, transition and mixture
probabilities (zeros stay zero, so a left-to-right model stays left-to-right) and no prior on the means;
the covariance of a component with soft count ``N`` and responsibility-weighted scatter ``S`` about its
*updated* mean is, by :data:`COVARIANCES`:

``map``
    ``(S + r·I) / (N + 1)``: the posterior mode under a weak inverse-Wishart prior (glu's recipe);
``ml``
    ``S / N + f·I``: maximum likelihood plus a floor ``f`` (the originals' mixsplit recipe, ``f = 0.01``);
    a component that lost its frames keeps its covariance.

A weight of 2 is the sequence twice, a weight of 0 leaves it out. hmmlearn's ``GMMHMM`` takes the scatter
about the means *before* the update (a generalised EM step); the tests train with hmmlearn as an
independent reference and check this E-step against it (``tests/hmm_reference.py``).

Shapes: ``S`` sequences, ``T`` frames (padded), ``Q`` states, ``M`` Gaussians per state, ``D`` features.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any, NamedTuple

import numpy as np

from glu.errors import ModelError
from glu.hmm.inference import forward_backward, gaussian_factors, log_component_densities, logsumexp


class GMMHMMParams(NamedTuple):
    """The parameters of a GMM-HMM: startprob (Q,), transmat (Q, Q), weights (Q, M), means (Q, M, D),
    covars (Q, M, D, D)."""

    startprob: np.ndarray
    transmat: np.ndarray
    weights: np.ndarray
    means: np.ndarray
    covars: np.ndarray


class FitResult(NamedTuple):
    """What :func:`fit` returns: the parameters after the last update, and the log-likelihood of the
    training data before each update (``history[i]`` is the model of iteration ``i``), shape (n_iter,)."""

    params: GMMHMMParams
    history: np.ndarray


def _pad(sequences: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lengths (S,), the mask of real frames (S, T), and all frames in order (N, D)."""
    lengths = np.array([len(x) for x in sequences])
    alive = np.arange(int(lengths.max()))[None, :] < lengths[:, None]
    return lengths, alive, np.concatenate(sequences)


COVARIANCES: tuple[str, ...] = ("map", "ml")
"""The covariance updates :func:`fit` knows (see the module docstring)."""


def check_covariance(covariance: str) -> None:
    """ModelError unless ``covariance`` is one of :data:`COVARIANCES`."""
    if covariance not in COVARIANCES:
        raise ModelError(f"unknown covariance update {covariance!r}; allowed: {', '.join(COVARIANCES)}")


EMPTY = 1e-10
"""A component with less soft count than this has lost its frames (``ml`` keeps its covariance)."""


# ------------------------------------------------------------------ weighted EM, sufficient statistics


@dataclass(frozen=True, eq=False)
class SufficientStats:
    """The expected sufficient statistics of a GMM-HMM, summed over sequences times their weights.

    Every field may carry the same leading batch axes ``...`` (one set of statistics per model).

    Attributes
    ----------
    start : array, shape (..., Q) — ``Σ_s w_s P(q_1 = q | G_s)``
    trans : array, shape (..., Q, Q) — ``Σ_s w_s Σ_t P(q_t = i, q_{t+1} = j | G_s)``
    counts : array, shape (..., Q, M) — ``Σ_s w_s Σ_t P(q_t = q, m_t = m | G_s)``
    first : array, shape (..., Q, M, D) — the same, times the frame ``x_t``
    second : array, shape (..., Q, M, D, D) — the same, times ``x_t x_tᵀ``
    loglik : array, shape (...) — ``Σ_s w_s log L(G_s)`` under the model of the E-step
    weight : array, shape (...) — ``Σ_s w_s``
    frames : array, shape (...) — ``Σ_s w_s T_s``
    """

    start: np.ndarray
    trans: np.ndarray
    counts: np.ndarray
    first: np.ndarray
    second: np.ndarray
    loglik: np.ndarray
    weight: np.ndarray
    frames: np.ndarray

    def __add__(self, other: SufficientStats) -> SufficientStats:
        """The statistics of both sets of sequences (field by field)."""
        return SufficientStats(*(getattr(self, f.name) + getattr(other, f.name) for f in fields(self)))

    def take(self, idx: Any) -> SufficientStats:
        """The statistics of the models at ``idx`` (a numpy index into the batch axes)."""
        return SufficientStats(*(getattr(self, f.name)[idx] for f in fields(self)))

    def put(self, idx: Any, new: SufficientStats) -> None:
        """Set the statistics of the models at ``idx`` to ``new`` (in place)."""
        for f in fields(self):
            getattr(self, f.name)[idx] = getattr(new, f.name)

    def scaled(self, factor: float | np.ndarray) -> SufficientStats:
        """Every field times ``factor`` (a number, or an array of the batch shape ``...``)."""
        factor = np.asarray(factor, dtype=float)
        out = []
        for f in fields(self):
            a = getattr(self, f.name)
            extra = a.ndim - factor.ndim
            out.append(a * factor.reshape(factor.shape + (1,) * extra))
        return SufficientStats(*out)

    @classmethod
    def zeros(
        cls, n_states: int, n_mix: int, n_features: int, batch: tuple[int, ...] = ()
    ) -> SufficientStats:
        """Statistics of no sequence, shapes as the attributes with ``... = batch``."""
        Q, M, D = n_states, n_mix, n_features
        shapes = ((Q,), (Q, Q), (Q, M), (Q, M, D), (Q, M, D, D), (), (), ())  # the fields' order
        return cls(*(np.zeros(batch + shape) for shape in shapes))


def sequence_weights(
    sequences: Sequence[np.ndarray], weights: Sequence[float] | np.ndarray | None
) -> np.ndarray:
    """``weights`` as a float array of shape (S,) (all ones for None); ModelError unless each is finite
    ≥ 0."""
    if weights is None:
        return np.ones(len(sequences))
    w = np.asarray(weights, dtype=float)
    if w.shape != (len(sequences),):
        raise ModelError(f"{len(sequences)} sequences need {len(sequences)} weights, got shape {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ModelError("sequence weights must be finite and ≥ 0")
    return w


def expected_stats(
    sequences: Sequence[np.ndarray], params: GMMHMMParams, weights: Sequence[float] | np.ndarray | None = None
) -> SufficientStats:
    """The E-step: sufficient statistics of ``sequences`` (arrays of shape (T_i, D)) under ``params``.

    Each sequence contributes its expected counts and moments times its weight (default 1); sequences of
    weight 0 are left out (as if absent, even when impossible under the model). Statistics of disjoint
    sets of sequences add up to the statistics of their union.

    >>> from glu.hmm.initialisation import init_left_to_right
    >>> rng = np.random.default_rng(0)
    >>> seqs = [np.cumsum(rng.normal(size=(30, 2)), axis=0) for _ in range(3)]
    >>> m = init_left_to_right(seqs, 3, 1, 0.01)
    >>> p = GMMHMMParams(m.startprob, m.transmat, m.weights, m.means, m.covars)
    >>> twice = expected_stats(seqs[:1] * 2 + seqs[1:], p)         # the first sequence twice …
    >>> weighted = expected_stats(seqs, p, [2.0, 1.0, 1.0])         # … or weighted 2
    >>> bool(np.allclose(twice.second, weighted.second)), float(weighted.weight)
    (True, 4.0)
    >>> parts = expected_stats(seqs[:1], p, [2.0]) + expected_stats(seqs[1:], p)
    >>> bool(np.allclose(parts.first, weighted.first))
    True
    """
    w = sequence_weights(sequences, weights)
    Q, M, D = params.means.shape
    keep = np.flatnonzero(w > 0)
    if len(keep) == 0:
        return SufficientStats.zeros(Q, M, D)
    seqs, w = [np.asarray(sequences[i], dtype=float) for i in keep], w[keep]
    lengths, alive, X = _pad(seqs)
    S, T = alive.shape
    chol_inv, log_norm = gaussian_factors(params.weights, params.covars)
    lc = log_component_densities(X, params.means, chol_inv, log_norm)  # (N, Q, M)
    log_b_flat = logsumexp(lc, axis=2)  # (N, Q)
    log_b = np.full((S, T, Q), -np.inf)
    log_b[alive] = log_b_flat
    gamma_padded, xi_sum, loglik = forward_backward(log_b, lengths, params.startprob, params.transmat, w)
    frame_w = np.repeat(w, lengths)  # (N,)
    with np.errstate(under="ignore"):
        post_mix = np.ones_like(lc) if M == 1 else np.exp(lc - log_b_flat[..., None])
        pcm = (gamma_padded[alive] * frame_w[:, None])[:, :, None] * post_mix  # (N, Q, M)
    return SufficientStats(
        start=w @ gamma_padded[:, 0],
        trans=xi_sum,
        counts=pcm.sum(axis=0),
        first=np.einsum("nqm,nd->qmd", pcm, X),
        second=np.einsum("nqm,ni,nj->qmij", pcm, X, X, optimize=True),
        loglik=np.asarray(float(w @ loglik)),
        weight=np.asarray(float(w.sum())),
        frames=np.asarray(float(w @ lengths)),
    )


def maximise(
    stats: SufficientStats,
    params: GMMHMMParams,
    covar_reg: float = 0.0,
    covariance: str = "map",
    covar_floor: float = 0.0,
) -> GMMHMMParams:
    """The M-step of :func:`fit` from sufficient statistics (any leading batch axes, the same in both).

    ``params`` is the model of the E-step: its zero start and transition probabilities stay zero (a
    left-to-right model stays left-to-right), ``"ml"`` keeps the covariance of a component that lost its
    frames. A state without any frame keeps its mixture weights, means and covariances (only possible with
    weighted or empty statistics).
    """
    check_covariance(covariance)
    D = params.means.shape[-1]
    startprob = np.where(params.startprob == 0, 0.0, np.maximum(stats.start, 0.0))
    total = startprob.sum(axis=-1, keepdims=True)
    startprob = np.where(total > 0, startprob / np.where(total > 0, total, 1.0), params.startprob)
    transmat = np.where(params.transmat == 0, 0.0, np.maximum(stats.trans, 0.0))
    row = transmat.sum(axis=-1, keepdims=True)
    transmat = np.where(row > 0, transmat / np.where(row == 0, 1.0, row), params.transmat)
    counts = stats.counts
    state = counts.sum(axis=-1, keepdims=True)  # (..., Q, 1)
    seen = state > 0
    weights = np.where(seen, counts / np.where(seen, state, 1.0), params.weights)
    m_d = np.where((weights == 0) & (stats.first == 0).all(axis=-1), 1.0, counts)
    with np.errstate(divide="ignore", invalid="ignore"):
        means = np.where(seen[..., None], stats.first / m_d[..., None], params.means)
    S = scatter(stats, means)
    n = counts[..., None, None]
    if covariance == "ml":
        with np.errstate(divide="ignore", invalid="ignore"):
            covars = S / n + covar_floor * np.eye(D)
        covars = np.where(n > EMPTY, covars, params.covars)
    else:
        covars = (covar_reg * np.eye(D) + S) / (n + 1.0)
        covars = np.where(seen[..., None, None], covars, params.covars)
    covars = 0.5 * (covars + np.swapaxes(covars, -1, -2))
    return GMMHMMParams(startprob, transmat, weights, means, covars)


def scatter(stats: SufficientStats, about: np.ndarray) -> np.ndarray:
    """``Σ p (x − m)(x − m)ᵀ`` of every component about ``m = about`` (shape (..., Q, M, D)) from the raw
    moments: ``second − first mᵀ − m firstᵀ + N m mᵀ``, shape (..., Q, M, D, D)."""
    outer_fm = stats.first[..., :, None] * about[..., None, :]
    return (
        stats.second
        - outer_fm
        - np.swapaxes(outer_fm, -1, -2)
        + stats.counts[..., None, None] * about[..., :, None] * about[..., None, :]
    )


def fit(
    sequences: Sequence[np.ndarray],
    init: GMMHMMParams,
    n_iter: int,
    tol: float,
    covar_reg: float = 0.0,
    covariance: str = "map",
    covar_floor: float = 0.0,
    weights: Sequence[float] | np.ndarray | None = None,
) -> FitResult:
    """Baum–Welch from ``init``: :func:`expected_stats` and :func:`maximise` until converged.

    ``sequences`` are arrays of shape (T_i, D), each counted ``weights[i]`` times (default all 1): EM for
    the weighted log-likelihood ``Σ_s w_s log L(G_s)``. ``history[i]`` is that log-likelihood under the
    model of iteration ``i``; EM stops after ``n_iter`` iterations or when an iteration gains less than
    ``tol`` (on the total, hmmlearn's ``tol``). ``covariance`` is one of :data:`COVARIANCES`, with the prior
    ``covar_reg`` (``map``) or the floor ``covar_floor`` (``ml``). The weighted log-likelihood never
    decreases with ``covariance="ml"`` and ``covar_floor=0`` (exact EM); with ``"map"`` its sum with the
    covariance prior's log-density never decreases (``tests/library/test_weighted_em.py``). Raises
    ``numpy.linalg.LinAlgError`` when a covariance stops being positive definite.
    """
    check_covariance(covariance)
    w = sequence_weights(sequences, weights)
    if not np.any(w > 0):
        raise ModelError("weighted EM needs at least one sequence of positive weight")
    params = GMMHMMParams(*(np.array(a, dtype=float) for a in init))
    history: list[float] = []
    for _ in range(n_iter):
        stats = expected_stats(sequences, params, w)
        history.append(float(stats.loglik))
        params = maximise(stats, params, covar_reg, covariance, covar_floor)
        if len(history) >= 2 and history[-1] - history[-2] < tol:
            break
    return FitResult(params, np.array(history))
