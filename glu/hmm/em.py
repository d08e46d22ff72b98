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

from glu.gestures.forward import TINY, gaussian_factors, log_component_densities


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


def _logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    m = a.max(axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore", under="ignore"):
        return np.log(np.exp(a - m).sum(axis=axis)) + np.squeeze(m, axis=axis)


def forward_backward(
    log_b: np.ndarray, lengths: np.ndarray, startprob: np.ndarray, transmat: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward–backward over a padded batch of sequences.

    Parameters
    ----------
    log_b : array, shape (S, T, Q) — emission log-densities; entries past a sequence's length are ignored
    lengths : array, shape (S,) — the length of each sequence (≥ 1)
    startprob : array, shape (Q,)
    transmat : array, shape (Q, Q)

    Returns
    -------
    gamma : array, shape (S, T, Q) — ``P(q_t | G)`` (0 past a sequence's end)
    xi_sum : array, shape (Q, Q) — expected transition counts, summed over sequences and frames
    loglik : array, shape (S,) — ``log L(G)`` of each sequence

    The recursions are scaled (each frame's largest emission factored out, each forward variable
    normalised), as :func:`glu.gestures.forward.forward_step`; when a frame's scaled mass underflows for
    some sequence, the whole batch is redone in the log domain (:func:`forward_backward_log`).
    """
    S, T, Q = log_b.shape
    alive = np.arange(T)[None, :] < lengths[:, None]  # (S, T)
    mx = np.where(alive, log_b.max(axis=2), 0.0)
    with np.errstate(under="ignore", invalid="ignore"):
        b = np.where(alive[..., None], np.exp(log_b - mx[..., None]), 1.0)  # padding: emits 1 everywhere
    eye = np.eye(Q)
    alpha = np.empty((S, T, Q))
    c = np.ones((S, T))
    a = startprob * b[:, 0]
    c[:, 0] = a.sum(axis=1)
    alpha[:, 0] = a / c[:, 0, None]
    for t in range(1, T):
        live = alive[:, t, None]
        a = np.where(live, (alpha[:, t - 1] @ transmat) * b[:, t], alpha[:, t - 1] @ eye)
        c[:, t] = a.sum(axis=1)
        if not np.all(c[:, t] > TINY):  # the scaled mass underflows for some sequence
            return forward_backward_log(log_b, lengths, startprob, transmat)
        alpha[:, t] = a / c[:, t, None]
    if not np.all(c[:, 0] > TINY):
        return forward_backward_log(log_b, lengths, startprob, transmat)
    loglik = np.where(alive, np.log(c) + mx, 0.0).sum(axis=1)
    beta = np.ones((S, T, Q))
    for t in range(T - 2, -1, -1):
        nxt = alive[:, t + 1, None]
        beta[:, t] = np.where(nxt, ((b[:, t + 1] * beta[:, t + 1]) @ transmat.T) / c[:, t + 1, None], 1.0)
    gamma = np.where(alive[..., None], alpha * beta, 0.0)
    gamma /= np.where(alive, gamma.sum(axis=2), 1.0)[..., None]  # as hmmlearn: renormalise each frame
    if T > 1:
        right = np.where(alive[:, 1:, None], b[:, 1:] * beta[:, 1:] / c[:, 1:, None], 0.0)
        xi_sum = transmat * np.einsum("sti,stj->ij", alpha[:, :-1], right, optimize=True)
    else:
        xi_sum = np.zeros((Q, Q))
    return gamma, xi_sum, loglik


def forward_backward_log(
    log_b: np.ndarray, lengths: np.ndarray, startprob: np.ndarray, transmat: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`forward_backward` in the log domain (slower; never underflows). Same arguments and returns."""
    S, T, Q = log_b.shape
    with np.errstate(divide="ignore"):
        log_a, log_pi = np.log(transmat), np.log(startprob)
    fwd = np.full((S, T, Q), -np.inf)
    fwd[:, 0] = log_pi + log_b[:, 0]
    for t in range(1, T):
        fwd[:, t] = _logsumexp(fwd[:, t - 1, :, None] + log_a, axis=1) + log_b[:, t]
    last = lengths - 1
    loglik = _logsumexp(fwd[np.arange(S), last], axis=1)
    bwd = np.zeros((S, T, Q))
    alive = np.arange(T)[None, :] < lengths[:, None]  # (S, T)
    for t in range(T - 2, -1, -1):
        step = _logsumexp(log_a + (log_b[:, t + 1] + bwd[:, t + 1])[:, None, :], axis=2)
        bwd[:, t] = np.where(alive[:, t + 1, None], step, 0.0)  # the last frame of a sequence has β = 1
    log_gamma = fwd + bwd - loglik[:, None, None]
    log_gamma = np.where(alive[..., None], log_gamma, -np.inf)
    log_gamma -= np.where(alive, _logsumexp(log_gamma, axis=2), 0.0)[..., None]  # as hmmlearn: renormalise
    if T > 1:
        pair = alive[:, 1:]  # transitions t → t+1 inside each sequence
        log_xi = (
            fwd[:, :-1, :, None]
            + log_a
            + (log_b[:, 1:] + bwd[:, 1:])[:, :, None, :]
            - loglik[:, None, None, None]
        )
        with np.errstate(under="ignore"):
            xi_sum = np.exp(np.where(pair[..., None, None], log_xi, -np.inf)).sum(axis=(0, 1))
    else:
        xi_sum = np.zeros((Q, Q))
    with np.errstate(under="ignore"):
        return np.exp(log_gamma), xi_sum, loglik


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
