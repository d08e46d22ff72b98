"""Reading p_HMM: the three readings, and temperature scaling against a brute-force search."""

from __future__ import annotations

import numpy as np
import pytest

from glu.errors import DataError
from glu.gestures.calibration import fit_calibration, fit_temperature, log_loss_at, p_hmm_reading


def softmax(s):
    e = np.exp(s - s.max(axis=-1, keepdims=True))
    return e / e.sum(axis=-1, keepdims=True)


def test_the_readings_by_hand():
    ll = np.array([[-120.0, -100.0, -160.0], [-5.0, -7.0, -6.0]])
    t = np.array([40, 4])
    np.testing.assert_allclose(p_hmm_reading(ll, t, "likelihood"), softmax(ll), rtol=1e-12)
    np.testing.assert_allclose(p_hmm_reading(ll, t, "per-frame"), softmax(ll / t[:, None]), rtol=1e-12)
    beta = np.array([0.1, 0.5])
    np.testing.assert_allclose(
        p_hmm_reading(ll, t, "calibrated", beta), softmax(ll * beta[:, None]), rtol=1e-12
    )
    impossible = np.full((1, 3), -np.inf)
    np.testing.assert_allclose(p_hmm_reading(impossible, np.array([3]), "likelihood"), [[1 / 3] * 3])
    with pytest.raises(DataError, match="needs its fitted"):
        p_hmm_reading(ll, t, "calibrated")
    with pytest.raises(DataError, match="allowed: likelihood, per-frame, calibrated"):
        p_hmm_reading(ll, t, "raw")


def test_fit_equals_a_brute_force_grid():
    rng = np.random.default_rng(0)
    ll = rng.normal(0, 20, size=(300, 3))
    y = np.array([rng.choice(3, p=p) for p in softmax(0.07 * ll)])
    beta = fit_temperature(ll, y)
    grid = np.linspace(0, 1, 20001)
    losses = [log_loss_at(b, ll - ll.max(1, keepdims=True), y) for b in grid]
    assert beta == pytest.approx(grid[int(np.argmin(losses))], abs=1e-4)
    assert log_loss_at(beta, ll - ll.max(1, keepdims=True), y) <= min(losses) + 1e-9


def test_fit_recovers_the_temperature_that_made_the_labels():
    rng = np.random.default_rng(1)
    ll = rng.normal(0, 10, size=(20000, 3))
    u = rng.random(len(ll))[:, None]
    y = (softmax(0.3 * ll).cumsum(axis=1) < u).sum(axis=1)
    assert fit_temperature(ll, y) == pytest.approx(0.3, abs=0.015)


def test_fit_bounds():
    rng = np.random.default_rng(2)
    ll = rng.normal(0, 10, size=(500, 3))
    assert fit_temperature(ll, ll.argmax(axis=1)) == 1.0  # always right: as sharp as allowed
    assert fit_temperature(ll, rng.integers(0, 3, 500)) < 0.02  # labels unrelated to the scores


def test_calibration_per_fraction():
    rng = np.random.default_rng(3)
    ll = rng.normal(0, 10, size=(400, 2, 3))
    y = ll[:, 1].argmax(axis=1)
    cal = fit_calibration(ll, y, [0.5, 1.0])
    assert cal.at(1.0) == 1.0 and cal.at(0.5) < 0.1 and cal.n_gestures == 400
    with pytest.raises(DataError, match="no calibration at fraction"):
        cal.at(0.3)


def test_fits_refuse_what_they_cannot_fit():
    ll = np.zeros((4, 3))
    for labels in (np.array([0, 1, 2]), np.array([0, 1, 2, 3]), np.array([0, -1, 2, 1])):
        with pytest.raises(
            DataError, match=r"fit_temperature: log-likelihoods \(n, K\) and labels \(n,\) in 0…K−1"
        ):
            fit_temperature(ll, labels)
    with pytest.raises(DataError, match="fit_temperature: log-likelihoods"):
        fit_temperature(np.zeros(4), np.zeros(4, dtype=int))
    with pytest.raises(DataError, match="no held-out gesture with finite log-likelihoods"):
        fit_temperature(np.full((2, 3), -np.inf), np.array([0, 1]))
    with pytest.raises(
        DataError, match=r"fit_calibration: log-likelihoods of shape \(n, 2, K\), not \(4, 3\)"
    ):
        fit_calibration(ll, np.zeros(4, dtype=int), [0.5, 1.0])
