"""Baum–Welch for GMM-HMMs with full covariances, all training sequences in one vectorised pass.

hmmlearn's ``GMMHMM.fit`` loops in Python over the sequences and, inside each, over the states and their
Gaussians; here the sequences are padded to a common length and pass through one forward and one
backward recursion together, and the emissions of every frame under every Gaussian are one array
operation — several times faster on the gesture corpora (``benchmarks/bench_hmm.py``).

The E-step is the usual one. The M-step re-estimates every parameter with flat Dirichlet priors on the
initial, transition and mixture probabilities (zeros stay zero, so a left-to-right model stays
left-to-right) and no prior on the means; the covariance of a component with soft count ``N`` and
responsibility-weighted scatter ``S`` about its *updated* mean is, by :data:`COVARIANCES`:

``map``
    ``(S + r·I) / (N + 1)``: the posterior mode under a weak inverse-Wishart prior (glu's recipe);
``ml``
    ``S / N + f·I``: maximum likelihood plus a floor ``f`` (the originals' mixsplit recipe, ``f = 0.01``);
    a component that lost its frames keeps its covariance;
``hmmlearn``
    ``(S_old + r·I) / (N + 1)`` with the scatter about the mean *before* the update, which is what
    hmmlearn 0.3's ``GMMHMM`` computes (a generalised EM step, not the maximiser). Kept to test this
    implementation against hmmlearn (``tests/test_hmm.py``: the same parameters and log-likelihood
    history).

Shapes: ``S`` sequences, ``T`` frames (padded), ``Q`` states, ``M`` Gaussians per state, ``D`` features.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from glu.hmm.inference import _logsumexp, forward_backward, gaussian_factors, log_component_densities


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


COVARIANCES: tuple[str, ...] = ("map", "ml", "hmmlearn")
"""The covariance updates :func:`fit` knows (see the module docstring)."""
EMPTY = 1e-10
"""A component with less soft count than this has lost its frames (``ml`` keeps its covariance)."""


def fit(
    sequences: Sequence[np.ndarray],
    init: GMMHMMParams,
    n_iter: int,
    tol: float,
    covar_reg: float = 0.0,
    covariance: str = "map",
    covar_floor: float = 0.0,
) -> FitResult:
    """Fit a GMM-HMM to ``sequences`` (arrays of shape (T_i, D)) by Baum–Welch from ``init``.

    ``tol`` is on the total log-likelihood (hmmlearn's ``tol``): EM stops after ``n_iter`` iterations or
    when an iteration gains less than ``tol``. ``covariance`` is one of :data:`COVARIANCES`, with the
    prior ``covar_reg`` (``map``, ``hmmlearn``) or the floor ``covar_floor`` (``ml``). Raises
    ``numpy.linalg.LinAlgError`` when a covariance stops being positive definite.
    """
    if covariance not in COVARIANCES:
        raise ValueError(f"unknown covariance update {covariance!r}; allowed: {', '.join(COVARIANCES)}")
    lengths, alive, X = _pad(sequences)
    S, T = alive.shape
    D = X.shape[1]
    startprob, transmat, weights, means, covars = (np.array(a, dtype=float) for a in init)
    Q, M = weights.shape
    history: list[float] = []
    for _ in range(n_iter):
        chol_inv, log_norm = gaussian_factors(weights, covars)
        lc = log_component_densities(X, means, chol_inv, log_norm)  # (N, Q, M), log w + log N
        log_b_flat = _logsumexp(lc, axis=2)  # (N, Q)
        log_b = np.full((S, T, Q), -np.inf)
        log_b[alive] = log_b_flat
        gamma_padded, xi_sum, loglik = forward_backward(log_b, lengths, startprob, transmat)
        history.append(float(loglik.sum()))
        gamma = gamma_padded[alive]  # (N, Q)
        with np.errstate(under="ignore"):
            if M == 1:
                post_mix = np.ones_like(lc)
            else:
                post_mix = np.exp(lc - log_b_flat[..., None])
            pcm = gamma[:, :, None] * post_mix  # (N, Q, M)
        start = gamma_padded[:, 0].sum(axis=0)
        post_mix_sum = pcm.sum(axis=0)
        post_sum = gamma.sum(axis=0)
        m_n = np.einsum("nqm,nd->qmd", pcm, X)
        old_means, old_covars = means, covars
        # M-step, as hmmlearn's GMMHMM._do_mstep with its default priors and ours on the covariances
        startprob = np.where(startprob == 0, 0.0, np.maximum(start, 0.0))
        startprob = startprob / startprob.sum()
        transmat = np.where(transmat == 0, 0.0, np.maximum(xi_sum, 0.0))
        row = transmat.sum(axis=1, keepdims=True)
        transmat = transmat / np.where(row == 0, 1.0, row)
        weights = post_mix_sum / post_sum[:, None]
        m_d = post_mix_sum.copy()
        m_d[(weights == 0) & (m_n == 0).all(axis=-1)] = 1.0
        means = m_n / m_d[:, :, None]
        centered = X[:, None, None, :] - (old_means if covariance == "hmmlearn" else means)[None]
        c_n = np.einsum("nqmi,nqmj->qmij", pcm[..., None] * centered, centered, optimize=True)
        if covariance == "ml":
            n = post_mix_sum[:, :, None, None]
            with np.errstate(divide="ignore", invalid="ignore"):
                covars = c_n / n + covar_floor * np.eye(D)
            covars = np.where(n > EMPTY, covars, old_covars)
        else:
            covars = (covar_reg * np.eye(D) + c_n) / (post_mix_sum + 1.0)[:, :, None, None]
        if len(history) >= 2 and history[-1] - history[-2] < tol:
            break
    return FitResult(GMMHMMParams(startprob, transmat, weights, means, covars), np.array(history))
