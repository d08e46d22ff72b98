"""The HMM recursions compiled (numba): the loops over frames that numpy can only run one step at a time.

The batched forward–backward of Baum–Welch and the batched scorer were array code whose cost on the
project's models (Q = 6 states, a few dozen sequences of 100–200 frames) was almost all per-step
dispatch: about 20 µs a frame for a few hundred multiplications. Here the same recursions run as
compiled loops, one sequence at a time, with the same scaling, the same underflow checks and the same
log-domain fallback; the callers (:func:`glu.gestures.baum_welch_batch.forward_backward_many`,
:func:`glu.gestures.batch.loglik_many`) keep their signatures and their numpy set-up.

What differs from the array code is only the order of some sums (a sum over states runs from the first
state to the last, where BLAS may group it otherwise), so results agree to rounding: 1e-12 relative in
the tests, which compare with the one-model paths and with hmmlearn. Loops use IEEE arithmetic (no
fast-math, no fused multiply-add), so the numbers are the same on every machine for the same inputs.

numba is imported when a kernel is first needed, so a notebook that never touches an HMM does not pay for
it, and the machine code is cached (``build/compiled/`` in a checkout, the user's cache folder for an
installed package: :attr:`glu.paths.Locations.compiled`; ``$NUMBA_CACHE_DIR`` wins), so only the first
process compiles (about 3 s) and later ones load it (about 0.5 s with numba's import).
"""

from __future__ import annotations

from functools import cache
from types import SimpleNamespace
from typing import Any

import numpy as np

from glu.gestures.forward import TINY


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


def _loglik_banked(X, starts, lengths, means, chol_inv, log_norm, startprob, transmat):
    A, Q, M, D = means.shape
    S = lengths.shape[0]
    out = np.zeros((S, A))
    diff = np.empty(D)
    lc = np.empty(M)
    log_b = np.empty(Q)
    alpha = np.empty(Q)
    pred = np.empty(Q)
    new = np.empty(Q)
    for s in range(S):
        for a in range(A):
            total = 0.0
            for t in range(lengths[s]):
                x = X[starts[s] + t]
                # emissions: log Σ_m w_m N(x; μ_qm, Σ_qm), as glu.gestures.forward.log_emissions
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
                # the predicted state, then glu.gestures.forward.scaled_step
                if t == 0:
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
                    total += np.log(csum) + mx
                    continue
                top = -np.inf  # the scaled mass underflowed: this frame in the log domain
                for q in range(Q):
                    new[q] = np.log(pred[q]) + log_b[q]
                    if new[q] > top:
                        top = new[q]
                if not np.isfinite(top):
                    for q in range(Q):
                        alpha[q] = 0.0
                    total += -np.inf
                    continue
                csum = 0.0
                for q in range(Q):
                    new[q] = np.exp(new[q] - top)
                    csum += new[q]
                for q in range(Q):
                    alpha[q] = new[q] / csum
                total += top + np.log(csum)
            out[s, a] = total
    return out


def _gmm_em(X, resp, reg_covar, tol, max_iter):
    """scikit-learn's GaussianMixture EM (full covariances) from initial responsibilities ``resp``.

    Round 0 is the M-step of ``resp``; each later round an E-step then an M-step; the fit stops after the
    M-step of the round whose mean log-likelihood changed by less than ``tol``, or after ``max_iter`` rounds.
    Returns weights, means, covariances and the rounds run (−1: a covariance was not positive definite).
    """
    n, D = X.shape
    M = resp.shape[1]
    eps10 = 10.0 * np.finfo(np.float64).eps
    weights = np.empty(M)
    means = np.empty((M, D))
    covs = np.empty((M, D, D))
    prec = np.zeros((M, D, D))  # the precisions' Cholesky factors, L⁻ᵀ
    L = np.zeros((D, D))
    inv = np.zeros((D, D))
    log_det = np.empty(M)
    lp = np.empty(M)
    log_2pi = np.log(2.0 * np.pi)
    lower = -np.inf
    n_iter = 0
    converged = False
    for it in range(max_iter + 1):
        if it > 0:  # E-step: the mean log-likelihood and the responsibilities
            previous = lower
            s = 0.0
            for i in range(n):
                top = -np.inf
                for k in range(M):
                    sq = 0.0
                    for c in range(D):
                        y = 0.0
                        for r in range(D):
                            y += (X[i, r] - means[k, r]) * prec[k, r, c]
                        sq += y * y
                    lp[k] = -0.5 * (D * log_2pi + sq) + log_det[k] + np.log(weights[k])
                    if lp[k] > top:
                        top = lp[k]
                acc = 0.0
                for k in range(M):
                    acc += np.exp(lp[k] - top)
                norm = top + np.log(acc)
                s += norm
                for k in range(M):
                    resp[i, k] = np.exp(lp[k] - norm)
            lower = s / n
            n_iter = it
            converged = abs(lower - previous) < tol
        # M-step: nk = Σ resp + 10 eps, means, covariances about the new means + reg_covar·I
        total = 0.0
        for k in range(M):
            nk = 0.0
            for i in range(n):
                nk += resp[i, k]
            nk += eps10
            weights[k] = nk
            total += nk
            for d in range(D):
                acc = 0.0
                for i in range(n):
                    acc += resp[i, k] * X[i, d]
                means[k, d] = acc / nk
            for r in range(D):
                for c in range(r, D):
                    acc = 0.0
                    for i in range(n):
                        acc += resp[i, k] * (X[i, r] - means[k, r]) * (X[i, c] - means[k, c])
                    covs[k, r, c] = acc / nk
                    covs[k, c, r] = covs[k, r, c]
                covs[k, r, r] += reg_covar
        for k in range(M):
            weights[k] /= n if it == 0 else total
        # the precisions' Cholesky factors: cov = L Lᵀ, prec = (L⁻¹)ᵀ
        for k in range(M):
            for r in range(D):
                for c in range(r + 1):
                    acc = covs[k, r, c]
                    for j in range(c):
                        acc -= L[r, j] * L[c, j]
                    if r == c:
                        if not acc > 0.0:
                            return weights, means, covs, -1
                        L[r, r] = np.sqrt(acc)
                    else:
                        L[r, c] = acc / L[c, c]
            for c in range(D):  # L⁻¹ column by column, by forward substitution
                for r in range(D):
                    inv[r, c] = 0.0
                for r in range(c, D):
                    acc = 1.0 if r == c else 0.0
                    for j in range(c, r):
                        acc -= L[r, j] * inv[j, c]
                    inv[r, c] = acc / L[r, r]
            ld = 0.0
            for r in range(D):
                for c in range(D):
                    prec[k, r, c] = inv[c, r]
                ld += np.log(prec[k, r, r])
            log_det[k] = ld
        if converged:
            break
    return weights, means, covs, n_iter


def _kmeans_step(X, old, csq, new, weight, labels, update):
    """One Lloyd round of scikit-learn's ``lloyd_iter_chunked_dense`` on one thread: each frame to its
    nearest centre (``‖c‖² − 2 x·c``, the first on ties), and, with ``update``, the sums of each cluster."""
    n, D = X.shape
    K = old.shape[0]
    if update:
        for j in range(K):
            weight[j] = 0.0
            for k in range(D):
                new[j, k] = 0.0
    for i in range(n):
        best = 0
        best_d = 0.0
        for j in range(K):
            dot = 0.0
            for k in range(D):
                dot += X[i, k] * old[j, k]
            d = csq[j] + -2.0 * dot
            if j == 0 or d < best_d:
                best_d = d
                best = j
        labels[i] = best
        if update:
            weight[best] += 1.0
            for k in range(D):
                new[best, k] += X[i, k]


def _kmeans_average(old, new, weight, shift):
    """scikit-learn's ``_average_centers`` (an empty cluster takes the biggest one's row as it is at that
    moment) and ``_center_shift``."""
    K, D = new.shape
    top = 0
    for j in range(1, K):
        if weight[j] > weight[top]:
            top = j
    for j in range(K):
        if weight[j] > 0:
            alpha = 1.0 / weight[j]
            for k in range(D):
                new[j, k] *= alpha
        else:
            for k in range(D):
                new[j, k] = new[top, k]
    for j in range(K):
        acc = 0.0
        for k in range(D):
            acc += (new[j, k] - old[j, k]) * (new[j, k] - old[j, k])
        shift[j] = np.sqrt(acc)


@cache
def _compiled() -> Any:
    """The kernels compiled by numba (or loaded from its cache): a namespace with one attribute each."""
    import numba

    from glu.paths import HERE

    if not numba.config.CACHE_DIR:  # never inside an installed package; $NUMBA_CACHE_DIR wins
        numba.config.CACHE_DIR = str(HERE.compiled)

    jit = numba.njit(cache=True, nogil=True, error_model="numpy")
    return SimpleNamespace(
        forward_backward_scaled=jit(_forward_backward_scaled),
        loglik_banked=jit(_loglik_banked),
        gmm_em=jit(_gmm_em),
        kmeans_step=jit(_kmeans_step),
        kmeans_average=jit(_kmeans_average),
    )


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
    ok : (S,) bool — False where a scaled mass fell to :data:`~glu.gestures.forward.TINY` or below at some
        frame (the sequence's other outputs are then meaningless: redo it in the log domain)
    """
    return _compiled().forward_backward_scaled(
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

    The emissions are :func:`glu.gestures.forward.log_emissions` and the recursion is
    :func:`glu.gestures.forward.forward_step` (scaled, each underflowing frame redone in the log domain),
    frame by frame; the log-likelihood is the sum of the steps in frame order, as
    :func:`glu.gestures.forward.forward_curve` accumulates it. Shapes as :class:`glu.gestures.batch.Bank`.
    """
    lengths = np.array([len(x) for x in sequences], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    X = np.ascontiguousarray(np.concatenate(sequences), dtype=np.float64)
    f = np.ascontiguousarray
    return _compiled().loglik_banked(
        X, starts, lengths, f(means, dtype=np.float64), f(chol_inv, dtype=np.float64),
        f(log_norm, dtype=np.float64), f(startprob, dtype=np.float64), f(transmat, dtype=np.float64),
    )  # fmt: skip


def gmm_em(
    X: np.ndarray, resp: np.ndarray, reg_covar: float, tol: float, max_iter: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """EM of a full-covariance Gaussian mixture as scikit-learn's ``GaussianMixture`` runs it.

    Parameters
    ----------
    X : array, shape (n, D) — the frames
    resp : array, shape (n, M) — the initial responsibilities (k-means' one-hot labels); overwritten
    reg_covar : added to every covariance's diagonal
    tol, max_iter : the stopping rule on the mean log-likelihood, and the most EM rounds

    Returns
    -------
    weights (M,), means (M, D), covariances (M, D, D), and the EM rounds run (``n_iter_``); −1 rounds
    when a covariance was not positive definite (the arrays are then meaningless).
    """
    weights, means, covs, n_iter = _compiled().gmm_em(
        np.ascontiguousarray(X, dtype=np.float64), np.ascontiguousarray(resp, dtype=np.float64),
        float(reg_covar), float(tol), int(max_iter),
    )  # fmt: skip
    return weights, means, covs, int(n_iter)


def kmeans_lloyd(X: np.ndarray, centers: np.ndarray, tol: float, max_iter: int) -> np.ndarray:
    """The labels of scikit-learn's ``_kmeans_single_lloyd`` (dense, unit weights, one thread) from
    ``centers``: Lloyd rounds until the labels repeat or the centres move less than ``tol`` (squared,
    summed), then, unless the labels repeated, one more assignment to the final centres.

    Parameters
    ----------
    X : array, shape (n, D) — the frames, centred on their mean (as ``KMeans.fit`` centres them)
    centers : array, shape (K, D) — the k-means++ centres (changed in place)
    tol, max_iter : ``KMeans``' scaled tolerance (``_tolerance``) and its ``max_iter``

    Returns the label of every frame (int32), as ``KMeans(...).fit(X).labels_``. The distances are summed
    in another order than the BLAS product scikit-learn calls, so a frame exactly halfway between two
    centres (to the last bit) may go the other way; the tests compare the labels on random, degenerate and
    the project's own problems.
    """
    k = _compiled()
    X = np.ascontiguousarray(X, dtype=np.float64)
    centers = np.ascontiguousarray(centers, dtype=np.float64)
    n, K = len(X), len(centers)
    new = np.zeros_like(centers)
    labels = np.full(n, -1, dtype=np.int32)
    labels_old = labels.copy()
    weight = np.zeros(K)
    shift = np.zeros(K)
    strict = False
    for _ in range(max_iter):
        k.kmeans_step(X, centers, np.einsum("ij,ij->i", centers, centers), new, weight, labels, True)
        if not weight.all():
            _relocate_empty_clusters(X, centers, new, weight, labels)
        k.kmeans_average(centers, new, weight, shift)
        centers, new = new, centers
        if np.array_equal(labels, labels_old):
            strict = True
            break
        if (shift**2).sum() <= tol:
            break
        labels_old[:] = labels
    if not strict:
        k.kmeans_step(X, centers, np.einsum("ij,ij->i", centers, centers), new, weight, labels, False)
    return labels


def _relocate_empty_clusters(
    X: np.ndarray, old: np.ndarray, new: np.ndarray, weight: np.ndarray, labels: np.ndarray
) -> None:
    """scikit-learn's ``_relocate_empty_clusters_dense`` (unit weights): each empty cluster takes the frame
    farthest from its centre, in ``argpartition``'s order."""
    empty = np.where(np.equal(weight, 0))[0].astype(np.int32)
    n_empty = empty.shape[0]
    distances = ((X - old[labels]) ** 2).sum(axis=1)
    far = np.argpartition(distances, -n_empty)[: -n_empty - 1 : -1].astype(np.int32)
    if np.max(distances) == 0:
        return
    for new_id, far_idx in zip(empty, far, strict=True):
        old_id = labels[far_idx]
        new[old_id] -= X[far_idx]
        new[new_id] = X[far_idx]
        weight[new_id] = 1.0
        weight[old_id] -= 1.0
