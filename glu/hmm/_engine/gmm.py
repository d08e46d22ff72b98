"""Compiled loops of the initial mixtures (numba): scikit-learn's ``GaussianMixture`` EM and ``KMeans``' Lloyd
rounds, called by :mod:`glu.hmm.initialisation` (whose functions are the ones to read and call)."""

from __future__ import annotations

import numpy as np

from glu.jit import compiled


def _gmm_em(X, resp, reg_covar, tol, max_iter):
    """scikit-learn's GaussianMixture EM (full covariances) from initial responsibilities ``resp``.

    Round 0 is the M-step of ``resp``; each later round an E-step then an M-step; the fit stops after the
    M-step of the round whose mean log-likelihood changed by less than ``tol``, or after ``max_iter`` rounds.
    Returns weights, means, covariances and the rounds run (−1: a covariance was not positive definite).
    """
    n, D = X.shape
    M = resp.shape[1]
    weights = np.empty(M)
    means = np.empty((M, D))
    covs = np.empty((M, D, D))
    prec = np.zeros((M, D, D))  # the precisions' Cholesky factors, L⁻ᵀ
    log_det = np.empty(M)
    lower = -np.inf
    n_iter = 0
    converged = False
    for it in range(max_iter + 1):
        if it > 0:  # E-step: the mean log-likelihood and the responsibilities
            previous = lower
            lower = _gmm_estep(X, weights, means, prec, log_det, resp)
            n_iter = it
            converged = abs(lower - previous) < tol
        _gmm_mstep(X, resp, reg_covar, it == 0, weights, means, covs)
        if not _gmm_precisions(covs, prec, log_det):
            return weights, means, covs, -1
        if converged:
            break
    return weights, means, covs, n_iter


def _gmm_estep(X, weights, means, prec, log_det, resp):
    """The E-step of :func:`_gmm_em`: each frame's responsibilities (into ``resp``) and the mean
    log-likelihood."""
    n, D = X.shape
    M = weights.shape[0]
    lp = np.empty(M)
    log_2pi = np.log(2.0 * np.pi)
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
    return s / n


def _gmm_mstep(X, resp, reg_covar, first, weights, means, covs):
    """The M-step of :func:`_gmm_em`: nk = Σ resp + 10 eps, means, covariances about the new means +
    reg_covar·I; the weights divided by n in the first round (as scikit-learn's initialisation), by Σ nk
    after."""
    n, D = X.shape
    M = resp.shape[1]
    eps10 = 10.0 * np.finfo(np.float64).eps
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
        weights[k] /= n if first else total


def _gmm_precisions(covs, prec, log_det):
    """The precisions' Cholesky factors (cov = L Lᵀ, prec = (L⁻¹)ᵀ) and their log-determinants, into
    ``prec`` and ``log_det``; False if a covariance is not positive definite."""
    M, D = covs.shape[0], covs.shape[1]
    L = np.zeros((D, D))
    inv = np.zeros((D, D))
    for k in range(M):
        for r in range(D):
            for c in range(r + 1):
                acc = covs[k, r, c]
                for j in range(c):
                    acc -= L[r, j] * L[c, j]
                if r == c:
                    if not acc > 0.0:
                        return False
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
    return True


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
    weights, means, covs, n_iter = compiled(_gmm_em)(
        np.ascontiguousarray(X, dtype=np.float64),
        np.ascontiguousarray(resp, dtype=np.float64),
        float(reg_covar),
        float(tol),
        int(max_iter),
    )
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
        compiled(_kmeans_step)(X, centers, np.einsum("ij,ij->i", centers, centers), new, weight, labels, True)
        if not weight.all():
            _relocate_empty_clusters(X, centers, new, weight, labels)
        compiled(_kmeans_average)(centers, new, weight, shift)
        centers, new = new, centers
        if np.array_equal(labels, labels_old):
            strict = True
            break
        if (shift**2).sum() <= tol:
            break
        labels_old[:] = labels
    if not strict:
        compiled(_kmeans_step)(
            X, centers, np.einsum("ij,ij->i", centers, centers), new, weight, labels, False
        )
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
