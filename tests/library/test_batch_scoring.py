"""Batched scoring of many sequences against every model: equal to the per-sequence forward and to
hmmlearn."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hmm_reference import to_hmmlearn
from scipy.interpolate import PchipInterpolator
from scipy.stats import multivariate_normal

from glu.errors import DataError
from glu.gestures.synthetic import pchip
from glu.hmm._engine.em_batch import quadratic_features
from glu.hmm.inference import left_to_right_transmat
from glu.hmm.model import GestureHMM
from glu.hmm.scoring import BatchScorer, bank_coefficients, forward_curves_batch, stack_models


def random_model(rng, Q, M, D=3, name=""):
    A = np.triu(rng.dirichlet(np.ones(Q), size=Q))
    A /= A.sum(1, keepdims=True)
    pi = np.zeros(Q)
    pi[0] = 1.0
    w = rng.dirichlet(np.ones(M), size=Q)
    mu = rng.normal(size=(Q, M, D))
    L = rng.normal(scale=0.3, size=(Q, M, D, D))
    cov = L @ np.swapaxes(L, -1, -2) + 0.05 * np.eye(D)
    return GestureHMM(pi, A, w, mu, cov, name=name)


@pytest.fixture(scope="module")
def bank():
    """Three models of different sizes (padding of Q and M is exercised)."""
    rng = np.random.default_rng(3)
    return [
        random_model(rng, 6, 3, name="a"),
        random_model(rng, 4, 2, name="b"),
        random_model(rng, 5, 1, name="c"),
    ]


def sequences(rng, n, lo=1, hi=60, D=3):
    return [rng.normal(size=(int(rng.integers(lo, hi)), D)) for _ in range(n)]


def test_equals_the_per_sequence_forward_for_every_prefix(bank):
    X = sequences(np.random.default_rng(0), 40)
    curves = BatchScorer(bank, batch_size=16).loglik_curves(X)  # several batches, unsorted lengths
    assert curves.shape == (40, max(len(x) for x in X), 3)
    for i, x in enumerate(X):
        for a, m in enumerate(bank):
            np.testing.assert_allclose(curves[i, : len(x), a], m.loglik_curve(x), rtol=1e-9, atol=1e-9)
        assert np.isnan(curves[i, len(x) :]).all()


def test_equals_hmmlearn_score(bank):
    X = sequences(np.random.default_rng(1), 12, lo=5)
    curves = BatchScorer(bank).loglik_curves(X)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for a, m in enumerate(bank):
            h = to_hmmlearn(m)
            for i, x in enumerate(X):
                np.testing.assert_allclose(curves[i, len(x) - 1, a], h.score(x), rtol=1e-9)
                t = len(x) // 2
                np.testing.assert_allclose(curves[i, t - 1, a], h.score(x[:t]), rtol=1e-9)


def test_emission_coefficients_give_the_mixture_log_densities(bank):
    """φ(x) · c_k = log w_k + log N(x; μ_k, Σ_k), against scipy, component by component."""
    stacked = stack_models(bank)
    center, coef = bank_coefficients(stacked)
    X = np.random.default_rng(2).normal(size=(30, 3))
    got = (quadratic_features(X, center) @ coef).reshape(30, *stacked.log_norm.shape)
    for a, m in enumerate(bank):
        for q in range(m.n_states):
            for k in range(m.n_mix):
                ref = np.log(m.weights[q, k]) + multivariate_normal(m.means[q, k], m.covars[q, k]).logpdf(X)
                np.testing.assert_allclose(got[:, a, q, k], ref, rtol=1e-10, atol=1e-9)
        assert (got[:, a, m.n_states :] < -1e299).all() and (got[:, a, :, m.n_mix :] < -1e299).all()


def test_underflowing_pairs_are_recomputed_exactly():
    """A frame far from every reachable state but near an unreachable one underflows the scaled forward."""
    means = np.array([[[0.0, 0, 0]], [[40.0, 40, 40]]])
    hmm = GestureHMM(
        [1.0, 0.0],
        left_to_right_transmat(2, 0.999),
        [[1.0], [1.0]],
        means,
        np.tile(np.eye(3) * 0.01, (2, 1, 1, 1)),
        name="x",
    )
    X = np.zeros((5, 3))
    X[1] = 40.0  # state 1 explains it; state 0 (where the mass is) gives exp(-1e5)
    scorer = BatchScorer([hmm])
    phi = quadratic_features(X, scorer.center)[:, :, None]  # (T, F, S=1)
    _, bad = forward_curves_batch(
        phi, scorer._coef_t, np.array([5]), scorer.bank.startprob, scorer._trans_t, 1
    )
    assert bad[0, 0]  # the scaled recursion underflowed ...
    curve = scorer.loglik_curves([X])[0, :, 0]
    np.testing.assert_allclose(curve, hmm.loglik_curve(X), rtol=1e-12)  # ... and the pair was recomputed
    assert np.isfinite(curve).all()


def test_recogniser_and_original_models(recognizer):
    """The fixture's bank (the original 2013 models on real data): batch equals the recogniser's own
    curves."""
    rng = np.random.default_rng(4)
    X = [rng.normal(scale=0.3, size=(int(rng.integers(20, 90)), 3)) - [0, 1, 1] for _ in range(10)]
    curves = BatchScorer(recognizer).loglik_curves(X)
    for i, x in enumerate(X):
        np.testing.assert_allclose(curves[i, : len(x)], recognizer.loglik_curve(x), rtol=1e-8, atol=1e-8)


def test_loglik_at_picks_prefixes_and_checks_them(bank):
    X = sequences(np.random.default_rng(5), 4, lo=10)
    scorer = BatchScorer(bank)
    ends = np.array([[1, len(x)] for x in X])
    got = scorer.loglik_at(X, ends)
    assert got.shape == (4, 2, 3)
    for i, x in enumerate(X):
        np.testing.assert_allclose(got[i, 1], [m.loglik(x) for m in bank], rtol=1e-9)
    with pytest.raises(DataError, match="between 1 and"):
        scorer.loglik_at(X, ends + 1)
    with pytest.raises(DataError, match="sequence 1"):
        scorer.loglik_curves([X[0], np.full((3, 3), np.nan)])
    for bad in (ends[:, 0], ends[:3]):
        with pytest.raises(DataError, match=r"ends must have shape \(n_sequences=4, n_prefixes\)"):
            scorer.loglik_at(X, bad)


def test_a_bank_needs_models_of_one_width():
    from glu.errors import ModelError

    rng = np.random.default_rng(6)
    with pytest.raises(ModelError, match="a bank needs at least one model"):
        stack_models([])
    with pytest.raises(ModelError, match=r"all models must have the same number of features, got \[2, 3\]"):
        stack_models([random_model(rng, 2, 1, D=3), random_model(rng, 2, 1, D=2)])


def test_pchip_equals_scipy_bit_for_bit():
    rng = np.random.default_rng(6)
    for k in range(300):
        K = int(rng.integers(2, 8))
        x = np.concatenate([[0.0], np.sort(rng.uniform(0.05, 0.95, K - 2)), [1.0]])
        if np.any(np.diff(x) < 1e-6):
            continue
        y = rng.normal(size=(K, 3))
        if k % 4 == 0 and K > 3:
            y[1:3] = y[1]  # a flat stretch: zero slopes
        u = np.linspace(-0.1, 1.1, 57)
        assert np.array_equal(pchip(x, y, u), PchipInterpolator(x, y, axis=0)(u))


def test_scores_any_number_of_features():
    rng = np.random.default_rng(7)
    bank = [random_model(rng, 3, 2, D=2), random_model(rng, 2, 2, D=2)]
    X = sequences(rng, 5, lo=3, D=2)
    curves = BatchScorer(bank).loglik_curves(X)
    for i, x in enumerate(X):
        for a, m in enumerate(bank):
            np.testing.assert_allclose(curves[i, : len(x), a], m.loglik_curve(x), rtol=1e-9)
