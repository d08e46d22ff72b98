"""Features as the original (docs/method.md §4.2): torso-centred hand, body-size factors over the middle 45–55
%."""

from __future__ import annotations

import math

import numpy as np
import pytest

from glu.errors import DataError
from glu.gestures.features import (
    HORIZONTAL_FALLBACK,
    OPENNI_JOINTS,
    VERTICAL_FALLBACK,
    log_features,
    middle_frames,
    normalisation_factors,
    skeleton_features,
)
from glu.gestures.recordings import load_features

J = {name: i for i, name in enumerate(OPENNI_JOINTS)}


def _skeleton(n=40, shoulder=0.4, neck=0.2, seed=0):
    """A skeleton with shoulders ``shoulder`` apart, neck ``neck`` above the torso, a wandering right hand."""
    rng = np.random.default_rng(seed)
    sk = rng.normal(size=(n, 15, 3))  # joints that do not matter are noise
    torso = np.array([0.3, 1.0, 2.5])
    sk[:, J["torso"]] = torso
    sk[:, J["neck"]] = torso + [0.0, neck, 0.0]
    sk[:, J["left_shoulder"]] = torso + [-shoulder / 2, neck, 0.0]
    sk[:, J["right_shoulder"]] = torso + [shoulder / 2, neck, 0.0]
    sk[:, J["right_hand"]] = torso + rng.normal(scale=0.3, size=(n, 3))
    return sk


def test_middle_frames_are_the_45_to_55_percent():
    assert middle_frames(100) == slice(45, 55)
    assert middle_frames(1) == slice(0, 1)
    for n in range(1, 400):
        s = middle_frames(n)
        idx = range(n)[s]
        assert len(idx) >= 1
        exact = [i for i in range(n) if 9 * n <= 20 * i < 11 * n]  # 0.45 n ≤ i < 0.55 n in integers
        if exact:
            assert list(idx) == exact


def test_features_closed_form():
    sk = _skeleton()
    f, norm = skeleton_features(sk)
    assert norm.horizontal == pytest.approx(0.4) and norm.vertical == pytest.approx(0.2)
    assert not norm.horizontal_fallback and not norm.vertical_fallback
    rel = sk[:, J["right_hand"]] - sk[:, J["torso"]]
    np.testing.assert_allclose(f, rel / [0.4, 0.2, 0.4], rtol=1e-12)


def test_factors_use_only_the_middle_frames():
    sk = _skeleton(n=100)
    # widen the shoulders outside frames 45..54: no effect
    for i in list(range(45)) + list(range(55, 100)):
        sk[i, J["right_shoulder"], 0] += 1.0
    assert normalisation_factors(sk).horizontal == pytest.approx(0.4)
    # widen them by 0.1 in half of the middle frames: the mean moves by 0.05
    sk[45:50, J["right_shoulder"], 0] += 0.1
    assert normalisation_factors(sk).horizontal == pytest.approx(0.45)


def test_fallback_constants_when_joints_are_missing():
    sk = _skeleton()
    sk[:, J["left_shoulder"]] = np.nan
    norm = normalisation_factors(sk)
    assert norm.horizontal == HORIZONTAL_FALLBACK == 0.33 and norm.horizontal_fallback
    assert norm.vertical == pytest.approx(0.2) and not norm.vertical_fallback
    sk[:, J["neck"]] = np.nan
    assert normalisation_factors(sk).vertical == VERTICAL_FALLBACK == 0.23
    assert normalisation_factors(sk, fallback=(330.0, 230.0)).horizontal == 330.0  # millimetre skeletons


def test_features_do_not_depend_on_position_or_body_size():
    sk = _skeleton(seed=3)
    f, _ = skeleton_features(sk)
    moved, _ = skeleton_features(sk + [1.5, -0.2, 0.7])
    bigger, _ = skeleton_features(sk * 1.2)
    np.testing.assert_allclose(moved, f, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(bigger, f, rtol=1e-10, atol=1e-12)


def test_bad_skeletons():
    with pytest.raises(DataError, match="shape"):
        skeleton_features(np.zeros((10, 14, 3)))
    with pytest.raises(DataError, match="the skeleton has no joint 'left_shoulder'; joints: torso, neck"):
        skeleton_features(np.zeros((10, 2, 3)) + 1, joints=("torso", "neck"))


def test_log_features_divide_by_1000(source):
    x = np.array([[644.291918, -809.62949, -934.764515]])
    np.testing.assert_array_equal(log_features(x), x / 1000)
    ref = np.loadtxt(source.hand_log("tap1_hand"))[:, 2:] / 1000
    (piece,) = load_features(source.hand_log("tap1_hand"), policy=None).pieces
    np.testing.assert_array_equal(piece.xyz, ref)


def test_synthetic_skeletons_give_the_original_body_factors():
    from glu.gestures.synthetic import synthesize_gestures

    for g in synthesize_gestures(8, seed=5, noise=0.0, spike_rate=0.0, dropout_rate=0.0):
        _, norm = skeleton_features(g.skeleton)
        # the synthetic body has shoulders 0.33 m and neck–torso 0.23 m apart at size 1
        assert norm.horizontal == pytest.approx(0.33 * g.size, rel=1e-9)
        assert norm.vertical == pytest.approx(0.23 * g.size, rel=1e-9)
        assert math.isfinite(norm.horizontal)


def test_the_middle_of_no_frames_is_refused():
    with pytest.raises(DataError, match="^a sequence needs at least one frame$"):
        middle_frames(0)
