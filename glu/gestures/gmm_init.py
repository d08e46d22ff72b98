"""The Gaussian mixtures that start each HMM state: scikit-learn's ``GaussianMixture`` fit, compiled.

:func:`glu.gestures.training.init_left_to_right` fits one mixture per state to the frames of that state's
time slices, as ``GaussianMixture(n_mix, covariance_type="full", reg_covar=…, random_state=seed,
n_init=1).fit(X)`` does. The experiments train hundreds of HMMs, so thousands of these small fits run;
scikit-learn spends most of its ~4 ms a fit in input validation and in numpy calls on arrays of a few
hundred frames. :func:`fit_gaussian_mixture` runs the same algorithm:

* the initial responsibilities from scikit-learn's own ``KMeans(n_mix, n_init=1)`` seeded with
  ``RandomState(seed)``, as ``GaussianMixture`` seeds it (one component: every frame in it, no k-means);
* then EM compiled (:func:`glu.gestures.kernels.gmm_em`): the M-step's ``nk = Σ resp + 10·eps``, means,
  covariances about the new means ``+ reg_covar·I``, the precisions' Cholesky factors; the E-step's
  log-densities and log-sum-exp; the same stopping rule (the mean log-likelihood changes by less than
  ``tol`` = 1e-3; at most 100 rounds).

The sums run in another order than scikit-learn's BLAS calls, so the result is scikit-learn's to rounding,
not bit for bit: ``tests/test_gmm_init.py`` compares every array with ``GaussianMixture``'s, and the number
of EM rounds with its ``n_iter_``, on random and degenerate problems (within 1e-14 of each array's scale
when written; the test allows 1e-10).

>>> import numpy as np
>>> X = np.random.default_rng(0).normal(size=(40, 3))
>>> w, mu, cov = fit_gaussian_mixture(X, 2, reg_covar=0.01, seed=0)
>>> w.shape, mu.shape, cov.shape, bool(np.isclose(w.sum(), 1.0))
((2,), (2, 3), (2, 3, 3), True)
"""

from __future__ import annotations

import warnings

import numpy as np

SKLEARN_TOL = 1e-3
"""``GaussianMixture``'s default ``tol``: EM stops when the mean log-likelihood changes by less."""
SKLEARN_MAX_ITER = 100
"""``GaussianMixture``'s default ``max_iter``."""


def load_libraries(n_mix: int) -> None:
    """Import what a fit calls (scikit-learn's KMeans, for ``n_mix`` > 1) now.

    Training runs under ``threadpoolctl.threadpool_limits(1)``, which binds only the libraries already
    loaded: a BLAS or OpenMP runtime loaded inside the limit (k-means uses both) runs a thread per core,
    and on these tiny problems that is several times slower. Call this before the limit.
    """
    if n_mix > 1:
        import sklearn.cluster  # noqa: F401


def fit_gaussian_mixture(
    X: np.ndarray,
    n_mix: int,
    reg_covar: float,
    seed: int,
    tol: float = SKLEARN_TOL,
    max_iter: int = SKLEARN_MAX_ITER,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A full-covariance Gaussian mixture fitted by EM as scikit-learn's ``GaussianMixture`` fits it (to rounding).

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
    tol=tol, max_iter=max_iter).fit(X)``. Raises ``ValueError`` (scikit-learn's message) when a
    covariance is not positive definite.
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
    from glu.gestures.kernels import gmm_em

    weights, means, covariances, n_iter = gmm_em(X, resp, reg_covar, tol, max_iter)
    if n_iter < 0:
        raise ValueError(
            "Fitting the mixture model failed because some components have ill-defined empirical "
            "covariance; increase reg_covar"
        )
    return weights, means, covariances
