"""Compiled loops (numba): the HMM recursions, compiled by :func:`glu.jit.compiled`.

The two recursions of the gesture HMMs, compiled: the scaled forward–backward of the E-step
(:func:`forward_backward_scaled`, the fast twin of :func:`glu.hmm.inference.forward_backward`, run by the one
E-step :func:`glu.hmm._engine.em_batch.estep`) and the forward recursion of scoring with its emissions
(:func:`loglik_banked`, the fast twin of :func:`glu.hmm.inference.forward_step`, run by
:func:`glu.hmm.scoring.loglik_many`). As array code their cost on the project's models (Q = 6 states, a few
dozen sequences of 100–200 frames) was almost all per-step dispatch: about 20 µs a frame for a few hundred
multiplications. Here they run as compiled loops, one sequence at a time, with the same scaling, the same
underflow checks and the same log-domain fallback. The mixture log-sum-exp of EM
(:func:`mixture_posteriors`) is here too: numpy's reductions over an axis of three Gaussians cost more than
the arithmetic. :mod:`glu.hmm.initialisation` compiles its k-means and EM loops the same way. The
prefix scorer of corpora (:class:`glu.hmm.scoring.BatchScorer`) stays array code: on its batches of
hundreds of sequences numpy's vectorised ``exp`` made it twice as fast as a compiled loop
(``benchmarks/bench_corpus.py``).

What differs from the array code is only the order of some sums (a sum over states runs from the first
state to the last, where BLAS may group it otherwise), so results agree to rounding: 1e-12 relative in
the tests, which compare with the one-model paths and with hmmlearn. Loops use IEEE arithmetic (no
fast-math, no fused multiply-add), so the numbers are the same on every machine for the same inputs.

numba is imported when a kernel is first needed, so a notebook that never touches an HMM does not pay for
it, and the machine code is cached (``build/compiled/`` in a checkout, the user's cache folder for an
installed package: :attr:`glu.paths.Locations.compiled`; ``$NUMBA_CACHE_DIR`` wins), so only the first
process compiles and later ones load it (both times measured in ``docs/speed.md``, the ``kernels`` table).
"""

from __future__ import annotations

import numpy as np

from glu.hmm.inference import TINY
from glu.jit import compiled


def _forward_backward_scaled(log_b, lengths, startprob, transmat):
    S, T, Q = log_b.shape
    alpha = np.zeros((S, T, Q))
    beta = np.zeros((S, T, Q))
    gamma = np.zeros((S, T, Q))
    b = np.zeros((S, T, Q))
    c = np.ones((S, T))
    xi = np.zeros((S, Q, Q))
    loglik = np.zeros(S)
    ok = np.ones(S, dtype=np.bool_)
    right = np.empty(Q)
    for s in range(S):
        L = lengths[s]
        A = transmat[s]
        for t in range(L):  # each frame's emissions scaled by the largest
            mx = -np.inf
            for j in range(Q):
                if log_b[s, t, j] > mx:
                    mx = log_b[s, t, j]
            for j in range(Q):
                b[s, t, j] = np.exp(log_b[s, t, j] - mx)
            loglik[s] += mx
        for t in range(L):
            total = 0.0
            for j in range(Q):
                if t == 0:
                    v = startprob[s, j] * b[s, 0, j]
                else:
                    acc = 0.0
                    for i in range(Q):
                        acc += alpha[s, t - 1, i] * A[i, j]
                    v = acc * b[s, t, j]
                alpha[s, t, j] = v
                total += v
            c[s, t] = total
            if not total > TINY:
                ok[s] = False
                break
            loglik[s] += np.log(total)
            for j in range(Q):
                alpha[s, t, j] /= total
        if not ok[s]:
            continue
        for j in range(Q):
            beta[s, L - 1, j] = 1.0
        for t in range(L - 2, -1, -1):
            for j in range(Q):
                right[j] = b[s, t + 1, j] * beta[s, t + 1, j] / c[s, t + 1]
            for i in range(Q):
                acc = 0.0
                for j in range(Q):
                    acc += right[j] * A[i, j]
                beta[s, t, i] = acc
                a_ti = alpha[s, t, i]
                for j in range(Q):
                    xi[s, i, j] += a_ti * right[j]
        for i in range(Q):
            for j in range(Q):
                xi[s, i, j] *= A[i, j]
        for t in range(L):
            total = 0.0
            for j in range(Q):
                v = alpha[s, t, j] * beta[s, t, j]
                gamma[s, t, j] = v
                total += v
            for j in range(Q):
                gamma[s, t, j] /= total
    return gamma, xi, loglik, ok


def _advance(x, a, first, alpha, means, chol_inv, log_norm, startprob, transmat, diff, lc, log_b, pred, new):
    """Model ``a``'s forward variable ``alpha`` (shape (Q,), updated in place) after frame ``x`` (the first
    frame when ``first``); returns the frame's log-likelihood increment. Scratch arrays: diff (D,), lc (M,),
    log_b, pred, new (Q,)."""
    Q, M, D = means.shape[1], means.shape[2], means.shape[3]
    # emissions: log Σ_m w_m N(x; μ_qm, Σ_qm), as glu.hmm.inference.log_emissions
    for q in range(Q):
        top = -np.inf
        for m in range(M):
            for d in range(D):
                diff[d] = x[d] - means[a, q, m, d]
            sq = 0.0
            for i in range(D):
                z = 0.0
                for j in range(D):
                    z += chol_inv[a, q, m, i, j] * diff[j]
                sq += z * z
            lc[m] = log_norm[a, q, m] - 0.5 * sq
            if lc[m] > top:
                top = lc[m]
        acc = 0.0
        for m in range(M):
            acc += np.exp(lc[m] - top)
        log_b[q] = np.log(acc) + top
    # the predicted state, then glu.hmm.inference.scaled_step
    if first:
        for q in range(Q):
            pred[q] = startprob[a, q]
    else:
        for j in range(Q):
            acc = 0.0
            for i in range(Q):
                acc += alpha[i] * transmat[a, i, j]
            pred[j] = acc
    mx = -np.inf
    for q in range(Q):
        if log_b[q] > mx:
            mx = log_b[q]
    csum = 0.0
    for q in range(Q):
        new[q] = pred[q] * np.exp(log_b[q] - mx)
        csum += new[q]
    if csum > TINY:
        for q in range(Q):
            alpha[q] = new[q] / csum
        return np.log(csum) + mx
    top = -np.inf  # the scaled mass underflowed: this frame in the log domain
    for q in range(Q):
        new[q] = np.log(pred[q]) + log_b[q]
        if new[q] > top:
            top = new[q]
    if not np.isfinite(top):
        for q in range(Q):
            alpha[q] = 0.0
        return -np.inf
    csum = 0.0
    for q in range(Q):
        new[q] = np.exp(new[q] - top)
        csum += new[q]
    for q in range(Q):
        alpha[q] = new[q] / csum
    return top + np.log(csum)


def _scratch(means):
    """The scratch arrays of :func:`_advance` for a bank's ``means`` (A, Q, M, D): diff, lc, log_b, pred,
    new."""
    Q, M, D = means.shape[1], means.shape[2], means.shape[3]
    return np.empty(D), np.empty(M), np.empty(Q), np.empty(Q), np.empty(Q)


def _loglik_banked(X, starts, lengths, means, chol_inv, log_norm, startprob, transmat):
    out = np.zeros((lengths.shape[0], means.shape[0]))
    alpha = np.empty(means.shape[1])
    diff, lc, log_b, pred, new = _scratch(means)
    for s in range(out.shape[0]):
        for a in range(out.shape[1]):
            total = 0.0
            for t in range(lengths[s]):
                x = X[starts[s] + t]
                total += _advance(
                    x,
                    a,
                    t == 0,
                    alpha,
                    means,
                    chol_inv,
                    log_norm,
                    startprob,
                    transmat,
                    diff,
                    lc,
                    log_b,
                    pred,
                    new,
                )
            out[s, a] = total
    return out


def _stream_step(x, first, alpha, total, means, chol_inv, log_norm, startprob, transmat):
    """Every model of a bank advanced by one frame ``x``: ``alpha`` (A, Q) and ``total`` (A,) in place."""
    diff, lc, log_b, pred, new = _scratch(means)
    for a in range(means.shape[0]):
        total[a] += _advance(
            x, a, first, alpha[a], means, chol_inv, log_norm, startprob, transmat, diff, lc, log_b, pred, new
        )


def _mixture_posteriors(lc, log_b, post):
    """For every (model, frame, state): ``log Σ_m exp(lc_m)`` and the mixture's responsibilities
    ``exp(lc_m) / Σ exp``, scaled by the largest term (0 when none is finite)."""
    K, N, Q, M = lc.shape
    for k in range(K):
        for n in range(N):
            for q in range(Q):
                top = -np.inf
                for m in range(M):
                    if lc[k, n, q, m] > top:
                        top = lc[k, n, q, m]
                if not np.isfinite(top):
                    top = 0.0
                mass = 0.0
                for m in range(M):
                    e = np.exp(lc[k, n, q, m] - top)
                    post[k, n, q, m] = e
                    mass += e
                log_b[k, n, q] = np.log(mass) + top
                for m in range(M):
                    post[k, n, q, m] /= mass


def forward_backward_scaled(
    log_b: np.ndarray, lengths: np.ndarray, startprob: np.ndarray, transmat: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The scaled forward–backward of each sequence of a padded batch, with its own parameters.

    Parameters
    ----------
    log_b : array, shape (S, T, Q) — emission log-densities (any values past a sequence's end); each
        frame is scaled by its largest before exponentiating
    lengths : int array, shape (S,) — each between 1 and T
    startprob : array, shape (S, Q); transmat : array, shape (S, Q, Q)

    Returns
    -------
    gamma : (S, T, Q) — ``P(q_t | G)``, renormalised per frame (0 past a sequence's end)
    xi : (S, Q, Q) — expected transition counts
    loglik : (S,) — ``log L(G)``
    ok : (S,) bool — False where a scaled mass fell to :data:`~glu.hmm.inference.TINY` or below at some
        frame (the sequence's other outputs are then meaningless: redo it in the log domain)
    """
    return compiled(_forward_backward_scaled)(
        np.ascontiguousarray(log_b, dtype=np.float64),
        np.ascontiguousarray(lengths, dtype=np.int64),
        np.ascontiguousarray(startprob, dtype=np.float64),
        np.ascontiguousarray(transmat, dtype=np.float64),
    )


def loglik_banked(
    sequences: list[np.ndarray],
    means: np.ndarray,
    chol_inv: np.ndarray,
    log_norm: np.ndarray,
    startprob: np.ndarray,
    transmat: np.ndarray,
) -> np.ndarray:
    """``log L(G | model)`` of every sequence under every model of a stacked bank, shape (S, A).

    The emissions are :func:`glu.hmm.inference.log_emissions` and the recursion is
    :func:`glu.hmm.inference.forward_step` (scaled, each underflowing frame redone in the log domain),
    frame by frame; the log-likelihood is the sum of the steps in frame order, as
    :func:`glu.hmm.inference.forward_curve` accumulates it. Shapes as :class:`glu.hmm.scoring.Bank`.
    """
    lengths = np.array([len(x) for x in sequences], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    X = np.ascontiguousarray(np.concatenate(sequences), dtype=np.float64)
    bank = (
        np.ascontiguousarray(a, dtype=np.float64) for a in (means, chol_inv, log_norm, startprob, transmat)
    )
    return compiled(_loglik_banked)(X, starts, lengths, *bank)


def stream_step(
    x: np.ndarray,
    first: bool,
    alpha: np.ndarray,
    total: np.ndarray,
    means: np.ndarray,
    chol_inv: np.ndarray,
    log_norm: np.ndarray,
    startprob: np.ndarray,
    transmat: np.ndarray,
) -> None:
    """Advance every model of a stacked bank by one frame ``x`` (D,): the scaled forward variables
    ``alpha`` (A, Q) and the log-likelihoods ``total`` (A,), both float64 and C-ordered, are updated in
    place — the same arithmetic, frame by frame, as :func:`loglik_banked` (the bank's arrays as there)."""
    compiled(_stream_step)(x, first, alpha, total, means, chol_inv, log_norm, startprob, transmat)


def mixture_posteriors(lc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each state's emission log-density and its mixture's responsibilities from the components'
    ``log w + log N`` ``lc``, shape (K, N, Q, M): returns ``log_b`` (K, N, Q) and ``post`` (K, N, Q, M)
    (numpy's ``logsumexp`` over the last axis and ``exp(lc − log_b)``, in one pass)."""
    lc = np.ascontiguousarray(lc, dtype=np.float64)
    log_b = np.empty(lc.shape[:-1])
    post = np.empty(lc.shape)
    compiled(_mixture_posteriors)(lc, log_b, post)
    return log_b, post
