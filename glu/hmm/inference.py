"""The forward algorithm of the gesture HMMs as pure functions over arrays.

Split the way dynamax splits its HMM inference: these functions know nothing of models, files or
training; they take documented arrays and return arrays. :class:`~glu.hmm.model.GestureHMM` scores a
whole sequence with :func:`forward_curve`; :class:`~glu.gestures.recognizer.GestureStream` advances every
model of a bank by one frame with the same :func:`forward_step`, so the batch and the streaming
recognisers are one recursion.

Shapes use ``T`` frames, ``Q`` states, ``M`` mixture components, ``D`` features, and any leading batch
axes ``...`` (``()`` for one model, ``(A,)`` for a bank of ``A`` models padded to a common ``Q`` and
``M``).

The recursion is *scaled*: the state carried from frame to frame is the normalised forward variable
``alpha_t(q) = P(q_t = q | G_1^t)`` plus the log-likelihood so far; each step factors the frame's largest
emission out before exponentiating, and a frame whose scaled emissions underflow for every reachable
state is redone in the log domain.

Example
-------
A two-state model that stays with probability 0.9, one Gaussian per state:

>>> import numpy as np
>>> means = np.array([[[0.0]], [[3.0]]])            # (Q=2, M=1, D=1)
>>> chol_inv, log_norm = gaussian_factors(np.ones((2, 1)), np.ones((2, 1, 1, 1)))
>>> X = np.array([[0.1], [0.2], [2.9]])             # (T=3, D=1)
>>> log_b = log_emissions(X, means, chol_inv, log_norm)
>>> log_b.shape
(3, 2)
>>> curve = forward_curve(log_b, np.array([1.0, 0.0]), np.array([[0.9, 0.1], [0.0, 1.0]]))
>>> curve.round(3)                                  # log L(G_1^t), t = 1, 2, 3
array([-0.924, -1.966, -5.049])
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

TINY = 1e-280
"""A frame whose scaled forward mass is below this is redone in the log domain."""
LOG_2PI = math.log(2 * math.pi)


class ForwardState(NamedTuple):
    """The forward recursion after frame t.

    Attributes
    ----------
    alpha : array, shape (..., Q) — ``P(q_t | G_1^t)``, rows sum to one (all zeros for a model to which the
        frames so far are impossible)
    loglik : array, shape (...) — ``log L(G_1^t)`` (``-inf`` when impossible)
    """

    alpha: np.ndarray
    loglik: np.ndarray


def gaussian_factors(weights: np.ndarray, covars: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Precompute what :func:`log_emissions` needs from mixture weights and full covariances.

    Parameters
    ----------
    weights : array, shape (..., M) — mixture weights (components of weight 0 may have any covariance)
    covars : array, shape (..., M, D, D) — symmetric positive-definite covariances

    Returns
    -------
    chol_inv : array, shape (..., M, D, D) — ``L⁻¹`` for the Cholesky factor ``L`` of each covariance
    log_norm : array, shape (..., M) — ``log w − (D/2) log 2π − log |L|`` (``-inf`` for weight 0)

    Raises ``numpy.linalg.LinAlgError`` if a used covariance is not positive definite.
    """
    D = covars.shape[-1]
    used = weights > 0
    safe = np.where(used[..., None, None], covars, np.eye(D))
    L = np.linalg.cholesky(safe)
    chol_inv = np.linalg.inv(L)
    with np.errstate(divide="ignore"):
        log_norm = (
            np.log(weights) - 0.5 * D * LOG_2PI - np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(axis=-1)
        )
    return chol_inv, log_norm


def log_component_densities(
    X: np.ndarray, means: np.ndarray, chol_inv: np.ndarray, log_norm: np.ndarray
) -> np.ndarray:
    """Weighted log-densities of every Gaussian of every state, ``log w_qm + log N(x_t; μ_qm, Σ_qm)``.

    Parameters
    ----------
    X : array, shape (T, D) — the frames
    means : array, shape (..., M, D)
    chol_inv, log_norm : arrays, shapes (..., M, D, D) and (..., M), from :func:`gaussian_factors`

    Returns
    -------
    array, shape (T, ..., M)
    """
    batch = means.ndim - 2
    diff = X.reshape((X.shape[0],) + (1,) * (batch + 1) + X.shape[1:]) - means[None]  # (T, ..., M, D)
    z = np.einsum("...ij,t...j->t...i", chol_inv, diff, optimize=False)
    return log_norm[None] - 0.5 * np.einsum("...i,...i->...", z, z)


def log_emissions(X: np.ndarray, means: np.ndarray, chol_inv: np.ndarray, log_norm: np.ndarray) -> np.ndarray:
    """Emission log-densities of Gaussian-mixture states, ``log p(x_t | q)``: the log-sum over the
    components of :func:`log_component_densities` (the same parameters).

    Returns
    -------
    array, shape (T, ...) — e.g. (T, Q) for one model, (T, A, Q) for a bank
    """
    lc = log_component_densities(X, means, chol_inv, log_norm)
    m = lc.max(axis=-1)
    with np.errstate(invalid="ignore"):
        return np.log(np.exp(lc - m[..., None]).sum(axis=-1)) + m


def forward_step(
    state: ForwardState | None, log_b: np.ndarray, startprob: np.ndarray, transmat: np.ndarray
) -> ForwardState:
    """Advance the scaled forward recursion by one frame.

    Parameters
    ----------
    state : the state after the previous frame, or None before the first frame
    log_b : array, shape (..., Q) — this frame's emission log-densities
    startprob : array, shape (..., Q)
    transmat : array, shape (..., Q, Q) — ``transmat[..., i, j] = P(q_{t+1} = j | q_t = i)``

    Returns
    -------
    the :class:`ForwardState` after this frame; ``loglik`` grows by ``log p(g_t | G_1^{t-1})``.
    """
    if state is None:
        pred, total = startprob, np.zeros(log_b.shape[:-1])
    else:
        a = state.alpha
        pred = a @ transmat if a.ndim == 1 else (a[..., None, :] @ transmat)[..., 0, :]
        total = state.loglik
    mx = log_b.max(axis=-1)
    alpha, step = scaled_step(pred, np.exp(log_b - mx[..., None]), mx, log_b)
    return ForwardState(alpha, total + step)


def scaled_step(
    pred: np.ndarray, b: np.ndarray, mx: np.ndarray, log_b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """One scaled forward step from the predicted state ``pred`` and the frame's scaled emissions
    ``b = exp(log_b − mx)``: the new normalised forward variable and the log-likelihood increment, shapes
    (..., Q) and (...). Where the scaled mass underflows (or a frame is impossible) that element is redone
    in the log domain; an impossible frame gives −∞ and a zero forward variable."""
    new = pred * b
    c = new.sum(axis=-1)
    ok = c > TINY
    if np.all(ok):
        return new / c[..., None], np.log(c) + mx
    with np.errstate(divide="ignore", invalid="ignore"):
        la = np.log(pred) + log_b
        m = la.max(axis=-1)
        finite = np.isfinite(m)
        m_safe = np.where(finite, m, 0.0)
        new_log = np.exp(la - m_safe[..., None])
        c_log = new_log.sum(axis=-1)
        step = np.where(ok, np.log(c) + mx, np.where(finite, m_safe + np.log(c_log), -np.inf))
        alpha = np.where(
            ok[..., None],
            new / np.where(ok, c, 1.0)[..., None],
            np.where(finite[..., None], new_log / np.where(finite, c_log, 1.0)[..., None], 0.0),
        )
    return alpha, step


def forward_curve(log_b: np.ndarray, startprob: np.ndarray, transmat: np.ndarray) -> np.ndarray:
    """Prefix log-likelihoods ``log L(G_1^t)`` for t = 1 … T by the forward algorithm.

    Parameters
    ----------
    log_b : array, shape (T, ..., Q) — emission log-densities (:func:`log_emissions`)
    startprob : array, shape (..., Q)
    transmat : array, shape (..., Q, Q)

    Returns
    -------
    array, shape (T, ...) — entry t-1 is ``log L(G_1^t)``; the last is the sequence's log-likelihood.

    The scaled recursion of :func:`forward_step` runs over all frames with the emissions scaled at once
    and underflow checked once at the end; only when some frame's scaled mass underflowed does it run
    again frame by frame through :func:`forward_step` (whose log-domain fallback handles it). Both give
    the same numbers where nothing underflows.
    """
    T = len(log_b)
    if T == 0:
        return np.empty(log_b.shape[:-1])
    mx = log_b.max(axis=-1)  # (T, ...)
    with np.errstate(all="ignore"):
        b = np.exp(log_b - mx[..., None])
        c = np.empty(log_b.shape[:-1])
        new = startprob * b[0]
        c[0] = new.sum(axis=-1)
        alpha = new / c[0][..., None]
        batch = alpha.ndim > 1
        for t in range(1, T):
            pred = (alpha[..., None, :] @ transmat)[..., 0, :] if batch else alpha @ transmat
            new = pred * b[t]
            c[t] = new.sum(axis=-1)
            alpha = new / c[t][..., None]
        if np.all(c > TINY):
            return np.cumsum(np.log(c) + mx, axis=0)
    out = np.empty(log_b.shape[:-1])  # underflow (or an impossible frame) somewhere: frame by frame
    state = None
    for t in range(T):
        state = forward_step(state, log_b[t], startprob, transmat)
        out[t] = state.loglik
    return out


def log_softmax(loglik: np.ndarray) -> np.ndarray:
    """``log p(a) = loglik[..., a] − logsumexp(loglik[..., :])`` (equal priors), shape as ``loglik``."""
    loglik = np.asarray(loglik, dtype=float)
    return loglik - logsumexp(loglik, axis=-1)[..., None]


def p_hmm_from_loglik(loglik: np.ndarray) -> np.ndarray:
    """The posterior ``p_HMM(A | G)`` with equal priors from log-likelihoods, shape (..., n_actions)."""
    return np.exp(log_softmax(loglik))


def left_to_right_transmat(n_states: int, stay: float) -> np.ndarray:
    """A left-to-right transition matrix, shape (Q, Q): stay with ``stay``, else move one state right."""
    A = np.zeros((n_states, n_states))
    for q in range(n_states - 1):
        A[q, q], A[q, q + 1] = stay, 1.0 - stay
    A[-1, -1] = 1.0
    return A


def logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    """``log Σ exp(a)`` along ``axis`` (−∞ where every term is −∞), scaled by the largest term: the shape of
    ``a`` without ``axis``."""
    m = a.max(axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore", under="ignore"):
        return np.log(np.exp(a - m).sum(axis=axis)) + np.squeeze(m, axis=axis)


def forward_backward(
    log_b: np.ndarray,
    lengths: np.ndarray,
    startprob: np.ndarray,
    transmat: np.ndarray,
    weights: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward–backward over a padded batch of sequences.

    Parameters
    ----------
    log_b : array, shape (S, T, Q) — emission log-densities; entries past a sequence's length are ignored
    lengths : array, shape (S,) — the length of each sequence (≥ 1)
    startprob : array, shape (Q,)
    transmat : array, shape (Q, Q)
    weights : array, shape (S,), optional — each sequence's weight in ``xi_sum`` (default: all 1, the
        plain sum; weighted EM, :func:`glu.hmm.em.expected_stats`)

    Returns
    -------
    gamma : array, shape (S, T, Q) — ``P(q_t | G)`` (0 past a sequence's end; never weighted)
    xi_sum : array, shape (Q, Q) — expected transition counts, summed over sequences (times their
        weights) and frames
    loglik : array, shape (S,) — ``log L(G)`` of each sequence

    The recursions are scaled (each frame's largest emission factored out, each forward variable
    normalised), as :func:`glu.hmm.inference.forward_step`; when a frame's scaled mass underflows for
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
    if not np.all(c[:, 0] > TINY):  # checked before dividing by it
        return forward_backward_log(log_b, lengths, startprob, transmat, weights)
    alpha[:, 0] = a / c[:, 0, None]
    for t in range(1, T):
        live = alive[:, t, None]
        a = np.where(live, (alpha[:, t - 1] @ transmat) * b[:, t], alpha[:, t - 1] @ eye)
        c[:, t] = a.sum(axis=1)
        if not np.all(c[:, t] > TINY):  # the scaled mass underflows for some sequence
            return forward_backward_log(log_b, lengths, startprob, transmat, weights)
        alpha[:, t] = a / c[:, t, None]
    loglik = np.where(alive, np.log(c) + mx, 0.0).sum(axis=1)
    beta = np.ones((S, T, Q))
    for t in range(T - 2, -1, -1):
        nxt = alive[:, t + 1, None]
        beta[:, t] = np.where(nxt, ((b[:, t + 1] * beta[:, t + 1]) @ transmat.T) / c[:, t + 1, None], 1.0)
    gamma = np.where(alive[..., None], alpha * beta, 0.0)
    gamma /= np.where(alive, gamma.sum(axis=2), 1.0)[..., None]  # as hmmlearn: renormalise each frame
    if T > 1:
        right = np.where(alive[:, 1:, None], b[:, 1:] * beta[:, 1:] / c[:, 1:, None], 0.0)
        if weights is None:
            xi_sum = transmat * np.einsum("sti,stj->ij", alpha[:, :-1], right, optimize=True)
        else:
            xi_sum = transmat * np.einsum("s,sti,stj->ij", weights, alpha[:, :-1], right, optimize=True)
    else:
        xi_sum = np.zeros((Q, Q))
    return gamma, xi_sum, loglik


def forward_backward_log(
    log_b: np.ndarray,
    lengths: np.ndarray,
    startprob: np.ndarray,
    transmat: np.ndarray,
    weights: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`forward_backward` in the log domain (slower; never underflows). Same arguments and returns."""
    S, T, Q = log_b.shape
    with np.errstate(divide="ignore"):
        log_a, log_pi = np.log(transmat), np.log(startprob)
    fwd = np.full((S, T, Q), -np.inf)
    fwd[:, 0] = log_pi + log_b[:, 0]
    for t in range(1, T):
        fwd[:, t] = logsumexp(fwd[:, t - 1, :, None] + log_a, axis=1) + log_b[:, t]
    last = lengths - 1
    loglik = logsumexp(fwd[np.arange(S), last], axis=1)
    bwd = np.zeros((S, T, Q))
    alive = np.arange(T)[None, :] < lengths[:, None]  # (S, T)
    for t in range(T - 2, -1, -1):
        step = logsumexp(log_a + (log_b[:, t + 1] + bwd[:, t + 1])[:, None, :], axis=2)
        bwd[:, t] = np.where(alive[:, t + 1, None], step, 0.0)  # the last frame of a sequence has β = 1
    log_gamma = fwd + bwd - loglik[:, None, None]
    log_gamma = np.where(alive[..., None], log_gamma, -np.inf)
    log_gamma -= np.where(alive, logsumexp(log_gamma, axis=2), 0.0)[..., None]  # as hmmlearn: renormalise
    if T > 1:
        pair = alive[:, 1:]  # transitions t → t+1 inside each sequence
        log_xi = (
            fwd[:, :-1, :, None]
            + log_a
            + (log_b[:, 1:] + bwd[:, 1:])[:, :, None, :]
            - loglik[:, None, None, None]
        )
        with np.errstate(under="ignore"):
            xi = np.exp(np.where(pair[..., None, None], log_xi, -np.inf))
            xi_sum = xi.sum(axis=(0, 1)) if weights is None else np.einsum("s,stij->ij", weights, xi)
    else:
        xi_sum = np.zeros((Q, Q))
    with np.errstate(under="ignore"):
        return np.exp(log_gamma), xi_sum, loglik
