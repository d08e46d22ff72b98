"""The shoulder line's body frame, and test people unlike the training ones (View.variety)."""

from __future__ import annotations

import numpy as np
import pytest

from glu.errors import DataError
from glu.gestures.features import OPENNI_JOINTS, skeleton_features, to_body_frame
from glu.gestures.synthetic import View, synthesize_gesture
from glu.gestures.synthetic_batch import gesture_features


def yaw(psi):
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def test_the_body_frame_undoes_a_turn_by_closed_form():
    rng = np.random.default_rng(0)
    rel = rng.normal(size=(20, 3))
    left, right = np.tile([-0.165, 0.21, 0.0], (20, 1)), np.tile([0.165, 0.21, 0.0], (20, 1))
    np.testing.assert_allclose(
        to_body_frame(rel, left, right), rel, atol=1e-15
    )  # facing the camera: unchanged
    for psi in (0.3, 1.7, -2.9):
        R = yaw(psi)
        turned = to_body_frame(rel @ R.T, left @ R.T, right @ R.T)
        np.testing.assert_allclose(turned, rel, atol=1e-12)


def test_the_shoulder_line_is_a_running_mean():
    rel = np.array([[1.0, 0.0, 0.0]] * 3)
    left = np.zeros((3, 3))
    right = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [np.nan, 0.0, 0.0]])  # frame 3: a shoulder missing
    out = to_body_frame(rel, left, right)
    u = np.array([1.0, -1.0]) / np.sqrt(2)  # mean of (1, 0) and (0, −1), kept through the missing frame
    np.testing.assert_allclose(out[0], [1.0, 0.0, 0.0])
    np.testing.assert_allclose(out[1], [u[0], 0.0, -u[1]])
    np.testing.assert_allclose(out[2], out[1])


def test_skeleton_features_in_the_body_frame():
    g = synthesize_gesture("tap", np.random.default_rng(1), noise=0.01, view=View(yaw_deg=50.0))
    body, _ = skeleton_features(g.skeleton, measure=False, frame="body")
    j = {n: OPENNI_JOINTS.index(n) for n in ("right_hand", "torso", "left_shoulder", "right_shoulder")}
    rel = g.skeleton[:, j["right_hand"]] - g.skeleton[:, j["torso"]]
    expected = to_body_frame(rel, g.skeleton[:, j["left_shoulder"]], g.skeleton[:, j["right_shoulder"]])
    np.testing.assert_allclose(body, expected / np.array([0.33, 0.23, 0.33]))
    with pytest.raises(DataError, match="unknown feature frame 'world'"):
        skeleton_features(g.skeleton, frame="world")


def test_a_turned_person_in_the_body_frame_is_the_front_one():
    kw = {"noise": 0.0, "spike_rate": 0.0, "dropout_rate": 0.0}
    front = synthesize_gesture(
        "grasp", np.random.default_rng(3), view=View(yaw_deg=0.0, body_frame=True), **kw
    )
    back = synthesize_gesture(
        "grasp", np.random.default_rng(3), view=View(yaw_deg=140.0, body_frame=True), **kw
    )
    seen = synthesize_gesture("grasp", np.random.default_rng(3), view=View(yaw_deg=140.0), **kw)
    np.testing.assert_allclose(back.features(), front.features(), atol=1e-12)
    assert not np.allclose(seen.features(), front.features(), atol=0.1)


@pytest.mark.parametrize(
    "view",
    [
        View(variety=1.0),
        View(variety=2.0, yaw_deg=60.0, body_frame=True),
        View(posture="seated", variety=0.5),
    ],
    ids=lambda v: v.describe(),
)
def test_the_batch_path_draws_the_same_varied_people(view):
    actions = ["grasp", "tap", "touch", "push"]

    def rngs():
        return [np.random.default_rng(10 + i) for i in range(4)]

    fast = gesture_features(actions, rngs(), noise=0.02, view=view)
    slow = [synthesize_gesture(a, r, noise=0.02, view=view) for a, r in zip(actions, rngs(), strict=True)]
    assert all(np.array_equal(x, g.features()) for x, g in zip(fast.features, slow, strict=True))


def test_variety_changes_the_movement_not_the_standard_people():
    kw = {"noise": 0.0, "spike_rate": 0.0, "dropout_rate": 0.0}
    a = synthesize_gesture("tap", np.random.default_rng(4), view=View(), **kw)
    b = synthesize_gesture("tap", np.random.default_rng(4), view=View(variety=0.0), **kw)
    c = synthesize_gesture("tap", np.random.default_rng(4), view=View(variety=1.0), **kw)
    np.testing.assert_array_equal(a.skeleton, b.skeleton)
    assert a.size == c.size  # the same person's body, another arm and style
    n = min(len(a.t), len(c.t))
    assert np.abs(a.features()[:n] - c.features()[:n]).max() > 0.05
    with pytest.raises(DataError, match="variety=5"):
        View(variety=5)
