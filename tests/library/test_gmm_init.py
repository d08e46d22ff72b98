"""The HMM states' initial mixtures: glu's compiled EM against scikit-learn's GaussianMixture, array for
array.

The sums run in another order than scikit-learn's, so the arrays agree to rounding (within 1e-14 of each
array's scale on these problems, degenerate ones included); 1e-10 is allowed here, and a different number
of EM rounds, a different stopping rule or a different M-step moves them by far more (1e-4 or more).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from glu.hmm.initialisation import fit_gaussian_mixture, init_left_to_right


def _sklearn_fit(X, n_mix, reg, seed):
    from sklearn.mixture import GaussianMixture

    gm = GaussianMixture(n_mix, covariance_type="full", reg_covar=reg, random_state=seed, n_init=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gm.fit(X)
    return gm


def _sklearn(X, n_mix, reg, seed):
    gm = _sklearn_fit(X, n_mix, reg, seed)
    return gm.weights_, gm.means_, gm.covariances_


def _assert_same(ours, theirs, what):
    """Every array equal to scikit-learn's within 1e-10 of that array's largest entry."""
    for name, a, b in zip(("weights", "means", "covariances"), ours, theirs, strict=True):
        assert a.shape == b.shape, (name, what)
        scale = max(float(np.abs(b).max()), 1e-300)
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * scale, err_msg=f"{name} {what}")


def _problems(n: int, seed: int):
    rng = np.random.default_rng(seed)
    for k in range(n):
        D, M = int(rng.integers(1, 7)), int(rng.integers(1, 5))
        X = rng.normal(size=(int(rng.integers(4 * M * D, 4 * M * D + 150)), D)) * rng.uniform(0.01, 2, D)
        X += rng.normal(size=D)
        if k % 4 == 0:
            X[: len(X) // 2] = X[0]  # half the frames on one point (a hand at rest)
        if k % 7 == 0:
            X[:, 0] = 1.5  # one coordinate constant: only reg_covar keeps the covariance definite
        yield X, M, float(rng.choice([1e-6, 1e-3, 0.03])), int(rng.integers(0, 2**31))


@pytest.mark.parametrize("chunk", range(4))
def test_the_mixtures_are_scikit_learns(chunk):
    with threadpool_limits(1):  # as training runs them
        for X, M, reg, seed in _problems(60, chunk):
            ours, theirs = fit_gaussian_mixture(X, M, reg, seed), _sklearn(X, M, reg, seed)
            _assert_same(ours, theirs, (X.shape, M, reg, seed))


@pytest.mark.parametrize("chunk", range(2))
def test_the_k_means_labels_are_scikit_learns(chunk):
    """Labels are discrete: they must be equal, on problems with repeated frames (empty clusters, ties in
    k-means++) and a constant coordinate, for 2 to 5 clusters."""
    from sklearn.cluster import KMeans

    from glu.hmm.initialisation import kmeans_labels

    n = 0
    with threadpool_limits(1):  # KMeans on one thread, as training runs it
        for X, M, _, seed in _problems(60, 20 + chunk):
            for K in sorted({M, 2, 3, 5}):
                if K > len(np.unique(X, axis=0)):
                    continue
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    expected = KMeans(K, n_init=1, random_state=np.random.RandomState(seed)).fit(X).labels_
                np.testing.assert_array_equal(
                    kmeans_labels(X, K, seed), expected, err_msg=str((X.shape, K, seed))
                )
                n += 1
    assert n > 150


def test_k_means_relocates_an_empty_cluster_as_scikit_learn_does():
    """k-means++ seeding practically never empties a cluster, so start the Lloyd rounds from centres one of
    which is far from every frame (it gets none in the first round and takes the farthest frame), against
    scikit-learn's own Lloyd loop from the same centres."""
    from sklearn.cluster._kmeans import _kmeans_single_lloyd

    from glu.hmm._engine.gmm import kmeans_lloyd

    with threadpool_limits(1):
        for seed in range(20):
            rng = np.random.default_rng(seed)
            X = rng.normal(size=(int(rng.integers(10, 80)), int(rng.integers(1, 4))))
            if seed % 2:
                X[: len(X) // 2] = X[0]  # repeated frames: ties in the farthest-frame choice
            X -= X.mean(axis=0)
            K = int(rng.integers(2, 5))
            centers = X[rng.choice(len(X), K - 1, replace=False)]
            centers = np.vstack([centers, np.full((1, X.shape[1]), 1e3)])  # the far one: emptied at once
            tol = 1e-4 * float(np.mean(np.var(X, axis=0)))
            expected, *_ = _kmeans_single_lloyd(
                X, np.ones(len(X)), centers.copy(), max_iter=300, tol=tol, n_threads=1
            )
            np.testing.assert_array_equal(
                kmeans_lloyd(X, centers.copy(), tol, 300), expected, err_msg=str(seed)
            )


def test_em_runs_as_many_rounds_as_scikit_learn():
    from sklearn.cluster import KMeans

    from glu.hmm._engine.gmm import gmm_em

    rounds = []
    with threadpool_limits(1):
        for X, M, reg, seed in _problems(60, 9):
            gm = _sklearn_fit(X, M, reg, seed)
            resp = np.zeros((len(X), M))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                labels = (
                    KMeans(M, n_init=1, random_state=np.random.RandomState(seed)).fit(X).labels_
                    if M > 1
                    else 0
                )
            resp[np.arange(len(X)), labels] = 1
            *_, n_iter = gmm_em(X, resp, reg, 1e-3, 100)
            assert n_iter == gm.n_iter_, (X.shape, M, reg, seed)
            rounds.append(n_iter)
    assert max(rounds) > 3  # the problems exercise more than the first rounds


def test_a_covariance_that_is_not_positive_definite_is_scikit_learns_error():
    X = np.zeros((20, 2))
    X[:, 0] = np.arange(20.0)  # the second coordinate constant and no regulariser: a singular covariance
    with pytest.raises(ValueError, match="ill-defined empirical covariance"):
        fit_gaussian_mixture(X, 1, 0.0, 0)


def test_the_initial_hmm_is_what_scikit_learn_gives(source):
    """init_left_to_right on real-shaped gesture features, against the same slices fitted by
    GaussianMixture."""
    from glu.gestures.corpus import gesture_sequences

    seqs = [s.xyz for s in gesture_sequences(source, include_test=False)][:6]
    with threadpool_limits(1):
        for n_mix, seed in ((1, 0), (3, 4)):
            model = init_left_to_right(seqs, 6, n_mix, seed=seed, covar_reg=0.03)
            for q in range(6):
                Xq = np.concatenate([X[np.minimum(np.arange(len(X)) * 6 // len(X), 5) == q] for X in seqs])
                w, mu, cov = _sklearn(Xq, n_mix, 0.03, seed)
                ours = (model.weights[q], model.means[q], model.covars[q])
                _assert_same(ours, (w, mu, 0.5 * (cov + np.swapaxes(cov, -1, -2))), (n_mix, seed, q))
