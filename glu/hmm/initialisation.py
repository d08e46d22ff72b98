"""The Gaussian mixtures that start each HMM state: scikit-learn's ``GaussianMixture`` fit, without
scikit-learn.

:func:`init_left_to_right` fits one mixture per state to the frames of that state's
time slices, as ``GaussianMixture(n_mix, covariance_type="full", reg_covar=…, random_state=seed,
n_init=1).fit(X)`` does. The experiments train hundreds of HMMs, so thousands of these small fits run;
scikit-learn spends most of its ~4 ms a fit in input validation and in numpy calls on arrays of a few
hundred frames. :func:`fit_gaussian_mixture` runs the same algorithm:

* the initial responsibilities from ``KMeans(n_mix, n_init=1)`` seeded with ``RandomState(seed)``, as
  ``GaussianMixture`` seeds it (one component: every frame in it, no k-means): :func:`kmeans_labels`,
  scikit-learn's k-means++ and Lloyd rounds (the labels are scikit-learn's on every problem of
  ``tests/library/test_gmm_init.py``; importing scikit-learn alone took 0.6–1 s in every kernel that trained
  an HMM);
* then EM compiled (:func:`gmm_em`): the M-step's ``nk = Σ resp + 10·eps``, means,
  covariances about the new means ``+ reg_covar·I``, the precisions' Cholesky factors; the E-step's
  log-densities and log-sum-exp; the same stopping rule (the mean log-likelihood changes by less than
  ``tol`` = 1e-3; at most 100 rounds).

The sums run in another order than scikit-learn's BLAS calls, so the result is scikit-learn's to rounding,
not bit for bit: ``tests/library/test_gmm_init.py`` compares every array with ``GaussianMixture``'s, and the
number of EM rounds with its ``n_iter_``, on random and degenerate problems (within 1e-14 of each array's
scale when written; the test allows 1e-10).

>>> import numpy as np
>>> X = np.random.default_rng(0).normal(size=(40, 3))
>>> w, mu, cov = fit_gaussian_mixture(X, 2, reg_covar=0.01, seed=0)
>>> w.shape, mu.shape, cov.shape, bool(np.isclose(w.sum(), 1.0))
((2,), (2, 3), (2, 3, 3), True)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from glu.errors import ModelError
from glu.hmm._engine.gmm import gmm_em, kmeans_lloyd
from glu.hmm.inference import left_to_right_transmat
from glu.hmm.model import GestureHMM

SKLEARN_TOL = 1e-3
"""``GaussianMixture``'s default ``tol``: EM stops when the mean log-likelihood changes by less."""
SKLEARN_MAX_ITER = 100
"""``GaussianMixture``'s default ``max_iter``."""


KMEANS_TOL = 1e-4
"""``KMeans``' default ``tol``, scaled by the mean variance of the frames (scikit-learn's ``_tolerance``)."""
KMEANS_MAX_ITER = 300
"""``KMeans``' default ``max_iter``."""


def kmeans_labels(X: np.ndarray, n_clusters: int, seed: int) -> np.ndarray:
    """``KMeans(n_clusters, n_init=1, random_state=RandomState(seed)).fit(X).labels_``, as scikit-learn
    computes it on one thread (what ``GaussianMixture`` starts from).

    The frames are centred on their mean; the k-means++ seeding makes scikit-learn's numpy calls in the same
    order with the same random draws (so it picks the same frames); the Lloyd rounds run compiled
    (:func:`kmeans_lloyd`), with scikit-learn's stopping rule, its relocation of empty
    clusters and its final assignment.

    >>> X = np.array([[0.0, 0.0], [0.1, 0.0], [5.0, 5.0], [5.1, 5.0], [9.0, 0.0], [9.1, 0.1]])
    >>> labels = kmeans_labels(X, 3, seed=0)
    >>> len(set(labels[:2].tolist())) == len(set(labels[2:4].tolist())) == 1, len(set(labels.tolist()))
    (True, 3)
    """
    X = np.array(X, dtype=np.float64, order="C")  # a copy: centred below, as KMeans does
    n = X.shape[0]
    if not 1 <= n_clusters <= n:
        raise ModelError(f"k-means needs between 1 and n_samples={n} clusters, got {n_clusters}")
    tol = np.mean(np.var(X, axis=0)) * KMEANS_TOL
    X -= X.mean(axis=0)
    x_squared_norms = np.einsum("ij,ij->i", X, X)
    weights = np.ones(n, dtype=X.dtype)
    rng = np.random.RandomState(seed)
    # scikit-learn's _kmeans_plusplus, with its _euclidean_distances (squared, dense, float64)
    centers = np.empty((n_clusters, X.shape[1]), dtype=X.dtype)
    n_local_trials = 2 + int(np.log(n_clusters))
    center_id = rng.choice(n, p=weights / weights.sum())
    centers[0] = X[center_id]
    closest_dist_sq = _squared_distances(centers[0, np.newaxis], X, x_squared_norms)
    current_pot = closest_dist_sq @ weights
    for c in range(1, n_clusters):
        rand_vals = rng.uniform(size=n_local_trials) * current_pot
        candidate_ids = np.searchsorted(np.cumsum(weights * closest_dist_sq), rand_vals)
        np.clip(candidate_ids, None, closest_dist_sq.size - 1, out=candidate_ids)
        distance_to_candidates = _squared_distances(X[candidate_ids], X, x_squared_norms)
        np.minimum(closest_dist_sq, distance_to_candidates, out=distance_to_candidates)
        candidates_pot = distance_to_candidates @ weights.reshape(-1, 1)
        best_candidate = np.argmin(candidates_pot)
        current_pot = candidates_pot[best_candidate]
        closest_dist_sq = distance_to_candidates[best_candidate]
        centers[c] = X[candidate_ids[best_candidate]]
    return kmeans_lloyd(X, centers, tol, KMEANS_MAX_ITER)


def _squared_distances(A: np.ndarray, X: np.ndarray, x_squared_norms: np.ndarray) -> np.ndarray:
    """scikit-learn's ``_euclidean_distances(A, X, Y_norm_squared=…, squared=True)`` for float64 arrays."""
    distances = -2 * (A @ X.T)
    distances += np.einsum("ij,ij->i", A, A)[:, None]
    distances += x_squared_norms.reshape(1, -1)
    np.maximum(distances, 0, out=distances)
    return distances


def fit_gaussian_mixture(
    X: np.ndarray,
    n_mix: int,
    reg_covar: float,
    seed: int,
    tol: float = SKLEARN_TOL,
    max_iter: int = SKLEARN_MAX_ITER,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A full-covariance Gaussian mixture fitted by EM as scikit-learn's ``GaussianMixture`` fits it (to
    rounding).

    Returns the weights, shape (M,), the means (M, D) and the covariances (M, D, D): ``gm.weights_``,
    ``gm.means_``, ``gm.covariances_`` of
    ``GaussianMixture(M, covariance_type="full", reg_covar=reg_covar, random_state=seed, n_init=1, tol=tol,
    max_iter=max_iter).fit(X)``. Raises ``ValueError`` (scikit-learn's message) when a covariance is not
    positive definite.

    Parameters
    ----------
    X : array, shape (n, D), float64, at least ``n_mix`` distinct rows
    n_mix : M, the number of components
    reg_covar : added to every covariance's diagonal
    seed : ``random_state`` of the k-means initialisation
    tol, max_iter : scikit-learn's stopping rule and limit
    """
    X = np.ascontiguousarray(X, dtype=np.float64)
    n = X.shape[0]
    resp = np.zeros((n, n_mix), dtype=X.dtype)
    if n_mix == 1:
        resp[:, 0] = 1  # what k-means with one cluster gives
    else:
        resp[np.arange(n), kmeans_labels(X, n_mix, seed)] = 1
    weights, means, covariances, n_iter = gmm_em(X, resp, reg_covar, tol, max_iter)
    if n_iter < 0:
        raise ValueError(
            "Fitting the mixture model failed because some components have ill-defined empirical "
            "covariance; increase reg_covar"
        )
    return weights, means, covariances


def init_left_to_right(
    sequences: Sequence[np.ndarray],
    n_states: int,
    n_mix: int,
    covar_reg: float,
    seed: int = 0,
    name: str = "",
) -> GestureHMM:
    """An initial left-to-right model: each sequence cut into ``n_states`` equal time slices, slice q → state
    q.

    The frames of slice q (over all sequences) give state q's mixture (scikit-learn's ``GaussianMixture``
    fit, seeded, as :func:`~glu.hmm.initialisation.fit_gaussian_mixture` computes it without scikit-learn;
    with too few frames, one Gaussian copied ``n_mix`` times with means spread along its main axis).
    Self-transition probabilities are ``1 - 1 / (mean frames per state)``, clipped to [0.5, 0.98].
    ``sequences`` are arrays of shape (T_i, D). Raises :class:`~glu.errors.ModelError`, naming the model
    (``name``) and ``covar_reg``, when a state's mixture has a singular covariance.
    """
    D = sequences[0].shape[1]
    slices: list[list[np.ndarray]] = [[] for _ in range(n_states)]
    for X in sequences:
        idx = np.minimum((np.arange(len(X)) * n_states) // len(X), n_states - 1)
        for q in range(n_states):
            slices[q].append(X[idx == q])
    weights = np.zeros((n_states, n_mix))
    means = np.zeros((n_states, n_mix, D))
    covars = np.zeros((n_states, n_mix, D, D))
    pooled_all = np.concatenate(sequences)
    for q in range(n_states):
        Xq = np.concatenate(slices[q]) if any(len(s) for s in slices[q]) else pooled_all
        if len(Xq) >= max(4 * n_mix * D, n_mix + 1) and len(np.unique(Xq, axis=0)) > n_mix:
            try:
                weights[q], means[q], covars[q] = fit_gaussian_mixture(Xq, n_mix, covar_reg, seed)
            except ValueError:  # a singular covariance (a feature that never varies in the slice's frames)
                raise ModelError(
                    f"the initial model of {name or 'the model'} failed: state {q + 1}'s frames have a "
                    "singular covariance (does a feature never vary?); try a larger covar_reg "
                    f"(now {covar_reg})"
                ) from None
        else:
            mu = Xq.mean(axis=0)
            cov = (np.cov(Xq.T) if len(Xq) > 1 else np.zeros((D, D))).reshape(D, D) + covar_reg * np.eye(D)
            w, v = np.linalg.eigh(cov)
            spread = np.linspace(-0.5, 0.5, n_mix) if n_mix > 1 else np.zeros(1)
            weights[q] = 1.0 / n_mix
            means[q] = mu + spread[:, None] * math.sqrt(w[-1]) * v[:, -1]
            covars[q] = cov
    covars = 0.5 * (covars + np.swapaxes(covars, -1, -2))
    mean_len = float(np.mean([len(X) for X in sequences]))
    stay = float(np.clip(1.0 - n_states / mean_len, 0.5, 0.98))
    startprob = np.eye(n_states)[0]  # every sequence starts in the first state
    return GestureHMM(startprob, left_to_right_transmat(n_states, stay), weights, means, covars, name=name)
