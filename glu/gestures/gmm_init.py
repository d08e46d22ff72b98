"""The Gaussian mixtures that start each HMM state: scikit-learn's ``GaussianMixture`` fit, without its overhead.

:func:`glu.gestures.training.init_left_to_right` fits one mixture per state to the frames of that state's
time slices, as ``GaussianMixture(n_mix, covariance_type="full", reg_covar=…, random_state=seed,
n_init=1).fit(X)`` does. The experiments train hundreds of HMMs, so thousands of these small fits ran,
each spending most of its ~4 ms in scikit-learn's input validation and array-API dispatch.
:func:`fit_gaussian_mixture` runs the same algorithm with the same operations in the same order:

* the initial responsibilities from scikit-learn's ``KMeans(n_mix, n_init=1)`` seeded with
  ``RandomState(seed)``, as ``GaussianMixture`` seeds it (one component: every frame in it, no k-means);
* the M-step's ``nk = Σ resp + 10·eps``, ``means = respᵀ X / nk``, covariances ``(resp·(X − μ)ᵀ)(X − μ) / nk
  + reg_covar·I``, and the precisions' Cholesky factors by LAPACK ``potrf`` and ``trtrs`` (what
  ``scipy.linalg.cholesky`` and ``solve_triangular`` call);
* the E-step's ``log N`` from those factors, its log-sum-exp written as scikit-learn writes it, and the
  same stopping rule (the mean log-likelihood changes by less than ``tol`` = 1e-3; at most 100 rounds).

So the result is scikit-learn's, bit for bit, with the versions this was checked against (scikit-learn 1.9,
SciPy 1.17, NumPy 2.4): ``tests/test_gmm_init.py`` compares every array with ``np.array_equal`` on random
and degenerate problems, and the notebooks' tables and figures are unchanged. With one component the
k-means step is skipped and the fit stops after its second round, as scikit-learn's does (the
responsibilities are exactly 1).

>>> import numpy as np
>>> X = np.random.default_rng(0).normal(size=(40, 3))
>>> w, mu, cov = fit_gaussian_mixture(X, 2, reg_covar=0.01, seed=0)
>>> w.shape, mu.shape, cov.shape, bool(np.isclose(w.sum(), 1.0))
((2,), (2, 3), (2, 3, 3), True)
"""

from __future__ import annotations

import math
import warnings

import numpy as np

SKLEARN_TOL = 1e-3
"""``GaussianMixture``'s default ``tol``: EM stops when the mean log-likelihood changes by less."""
SKLEARN_MAX_ITER = 100
"""``GaussianMixture``'s default ``max_iter``."""
_EPS10 = 10 * np.finfo(np.float64).eps


def load_libraries(n_mix: int) -> None:
    """Import what a fit calls (SciPy's LAPACK, and scikit-learn's KMeans for ``n_mix`` > 1) now.

    Training runs under ``threadpoolctl.threadpool_limits(1)``, which binds only the libraries already
    loaded: a BLAS loaded inside the limit runs a thread per core, and on these tiny matrices that is
    several times slower (0.63 s against 2.6 s for 180 three-component fits). Call this before the limit.
    """
    import scipy.linalg  # noqa: F401

    if n_mix > 1:
        import sklearn.cluster  # noqa: F401


def _lapack() -> tuple:
    from scipy.linalg import get_lapack_funcs

    probe = np.eye(2)
    return get_lapack_funcs(("potrf", "trtrs"), (probe, probe))


def _parameters(X: np.ndarray, resp: np.ndarray, reg_covar: float) -> tuple[np.ndarray, ...]:
    """scikit-learn's ``_estimate_gaussian_parameters`` (full covariances): nk, means, covariances."""
    nk = np.sum(resp, axis=0) + _EPS10
    means = (resp.T @ X) / nk[:, np.newaxis]
    M, D = means.shape
    covariances = np.empty((M, D, D), dtype=X.dtype)
    for k in range(M):
        diff = X - means[k, :]
        covariances[k, :, :] = ((resp[:, k] * diff.T) @ diff) / nk[k]
        covariances[k].flat[: D * D : D + 1] += reg_covar
    return nk, means, covariances


def _precision_cholesky(covariances: np.ndarray, potrf, trtrs) -> np.ndarray:  # type: ignore[no-untyped-def]
    """scikit-learn's ``_compute_precision_cholesky`` (full): ``solve_triangular(cholesky(Σ), I).T`` per component."""
    M, D, _ = covariances.shape
    eye = np.eye(D, dtype=covariances.dtype)
    out = np.empty((M, D, D), dtype=covariances.dtype)
    for k in range(M):
        chol, info = potrf(covariances[k, :, :], lower=True, overwrite_a=False, clean=True)
        if info != 0:
            raise ValueError(
                "Fitting the mixture model failed because some components have ill-defined empirical "
                "covariance; increase reg_covar"
            )
        if chol.flags.f_contiguous:  # as solve_triangular hands it to trtrs
            x, info = trtrs(chol, eye, overwrite_b=False, lower=True, trans=0, unitdiag=False)
        else:
            x, info = trtrs(chol.T, eye, overwrite_b=False, lower=False, trans=1, unitdiag=False)
        out[k, :, :] = x.T
    return out


def _e_step(X: np.ndarray, weights: np.ndarray, means: np.ndarray, prec_chol: np.ndarray) -> tuple:
    """scikit-learn's E-step: (mean log-likelihood, log responsibilities)."""
    n, D = X.shape
    M = means.shape[0]
    log_det = np.sum(np.log(np.reshape(prec_chol, (M, -1))[:, :: D + 1]), axis=1)
    log_prob = np.empty((n, M), dtype=X.dtype)
    for k in range(M):
        y = (X @ prec_chol[k, :, :]) - (means[k, :] @ prec_chol[k, :, :])
        log_prob[:, k] = np.sum(np.square(y), axis=1)
    weighted = (-0.5 * (D * math.log(2 * math.pi) + log_prob) + log_det) + np.log(weights)
    norm = _logsumexp_rows(weighted)
    with np.errstate(under="ignore"):
        log_resp = weighted - norm[:, np.newaxis]
    return np.mean(norm), log_resp


def _logsumexp_rows(a: np.ndarray) -> np.ndarray:
    """scikit-learn's ``_logsumexp(a, axis=1)`` (its own, after SciPy's), operation for operation."""
    a_max = np.max(a, axis=1, keepdims=True)
    index_max = a == a_max
    a = np.asarray(a, copy=True)
    a[index_max] = -np.inf
    m = np.sum(index_max.astype(a.dtype), axis=1, keepdims=True, dtype=a.dtype)
    shift = np.where(np.isfinite(a_max), a_max, 0)
    s = np.sum(np.exp(a - shift), axis=1, keepdims=True, dtype=a.dtype)
    s = np.where(s == 0, s, s / m)
    return np.squeeze(np.log1p(s) + np.log(m) + a_max, axis=1)


def fit_gaussian_mixture(
    X: np.ndarray,
    n_mix: int,
    reg_covar: float,
    seed: int,
    tol: float = SKLEARN_TOL,
    max_iter: int = SKLEARN_MAX_ITER,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A full-covariance Gaussian mixture fitted by EM exactly as scikit-learn's ``GaussianMixture`` fits it.

    Parameters
    ----------
    X : array, shape (n, D), float64, at least ``n_mix`` distinct rows
    n_mix : M, the number of components
    reg_covar : added to every covariance's diagonal
    seed : ``random_state`` of the k-means initialisation
    tol, max_iter : scikit-learn's stopping rule and limit

    Returns
    -------
    weights (M,), means (M, D), covariances (M, D, D): ``gm.weights_``, ``gm.means_``, ``gm.covariances_``
    of ``GaussianMixture(M, covariance_type="full", reg_covar=reg_covar, random_state=seed, n_init=1,
    tol=tol, max_iter=max_iter).fit(X)``.
    """
    X = np.ascontiguousarray(X, dtype=np.float64)
    n = X.shape[0]
    resp = np.zeros((n, n_mix), dtype=X.dtype)
    if n_mix == 1:
        resp[:, 0] = 1  # what k-means with one cluster gives
    else:
        from sklearn.cluster import KMeans

        with warnings.catch_warnings():  # e.g. fewer distinct clusters than asked: the fit goes on, as before
            warnings.simplefilter("ignore")
            labels = (
                KMeans(n_clusters=n_mix, n_init=1, random_state=np.random.RandomState(seed)).fit(X).labels_
            )
        resp[np.arange(n), labels] = 1
    potrf, trtrs = _lapack()
    nk, means, covariances = _parameters(X, resp, reg_covar)
    weights = nk / n
    prec_chol = _precision_cholesky(covariances, potrf, trtrs)
    lower_bound = -np.inf
    for _ in range(max_iter):
        previous = lower_bound
        lower_bound, log_resp = _e_step(X, weights, means, prec_chol)
        weights, means, covariances = _parameters(X, np.exp(log_resp), reg_covar)
        weights = weights / np.sum(weights)
        prec_chol = _precision_cholesky(covariances, potrf, trtrs)
        if abs(lower_bound - previous) < tol:
            break
    return weights, means, covariances
