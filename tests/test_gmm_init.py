"""The HMM states' initial mixtures: glu's lean EM against scikit-learn's GaussianMixture, array for array."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from glu.gestures.gmm_init import fit_gaussian_mixture
from glu.gestures.training import init_left_to_right


def _sklearn(X, n_mix, reg, seed):
    from sklearn.mixture import GaussianMixture

    gm = GaussianMixture(n_mix, covariance_type="full", reg_covar=reg, random_state=seed, n_init=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gm.fit(X)
    return gm.weights_, gm.means_, gm.covariances_


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
def test_the_mixtures_are_scikit_learns_bit_for_bit(chunk):
    with threadpool_limits(1):  # as training runs them
        for X, M, reg, seed in _problems(60, chunk):
            ours, theirs = fit_gaussian_mixture(X, M, reg, seed), _sklearn(X, M, reg, seed)
            for a, b in zip(ours, theirs, strict=True):
                assert a.shape == b.shape and np.array_equal(a, b), (X.shape, M, reg, seed)


def test_the_initial_hmm_is_what_scikit_learn_gives(source):
    """init_left_to_right on real-shaped gesture features, against the same slices fitted by GaussianMixture."""
    from glu.gestures.corpus import gesture_sequences

    seqs = [s.xyz for s in gesture_sequences(source, include_test=False)][:6]
    with threadpool_limits(1):
        for n_mix, seed in ((1, 0), (3, 4)):
            model = init_left_to_right(seqs, 6, n_mix, seed=seed, covar_reg=0.03)
            for q in range(6):
                Xq = np.concatenate([X[np.minimum(np.arange(len(X)) * 6 // len(X), 5) == q] for X in seqs])
                w, mu, cov = _sklearn(Xq, n_mix, 0.03, seed)
                np.testing.assert_array_equal(model.weights[q], w)
                np.testing.assert_array_equal(model.means[q], mu)
                np.testing.assert_array_equal(model.covars[q], 0.5 * (cov + np.swapaxes(cov, -1, -2)))
