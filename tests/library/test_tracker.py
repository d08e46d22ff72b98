"""The occluding skeleton tracker (glu.gestures.views.track): what it reports side-on and from behind,
checked on skeletons built by hand and on synthetic gestures, and the batch path bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from glu.errors import DataError
from glu.gestures.features import OPENNI_JOINTS, to_body_frame
from glu.gestures.synthetic import View, synthesize_gesture
from glu.gestures.synthetic_batch import gesture_features
from glu.gestures.views import track, tracker_state

J = {j: i for i, j in enumerate(OPENNI_JOINTS)}
CLEAN = {"noise": 0.0, "spike_rate": 0.0, "dropout_rate": 0.0}


def _turned(yaw_deg: float, distance: float = 2.0) -> np.ndarray:
    """A standing body 2 m in front of the camera (at the origin, looking along −z), turned by yaw: the
    shoulders ±0.165 m, the hands below them, one frame."""
    body = {
        "torso": (0.0, 0.0, 0.0),
        "left_shoulder": (-0.165, 0.21, 0.0),
        "right_shoulder": (0.165, 0.21, 0.0),
        "left_hand": (-0.22, -0.3, 0.04),
        "right_hand": (0.3, -0.1, -0.3),
    }
    c, s = np.cos(np.deg2rad(yaw_deg)), np.sin(np.deg2rad(yaw_deg))
    rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    skel = np.zeros((1, len(OPENNI_JOINTS), 3))
    for name, p in body.items():
        skel[0, J[name]] = rot @ np.array(p) + np.array([0.0, 0.0, -distance])
    return skel


def test_states_by_turn():
    assert [tracker_state(y) for y in (0, 45, 60, 61, 90, 120, 121, 180, -179, -90, 300)] == [
        "sees all", "sees all", "sees all", "far shoulder lost", "far shoulder lost", "far shoulder lost",
        "left and right swapped", "left and right swapped", "left and right swapped", "far shoulder lost",
        "sees all",
    ]  # fmt: skip


@pytest.mark.parametrize("yaw", [0.0, 40.0, -55.0])
def test_facing_enough_everything_is_where_it_is(yaw):
    skel = _turned(yaw)
    assert np.array_equal(track(skel, np.deg2rad(yaw), View(tracker="occluding")), skel)
    assert track(skel, np.deg2rad(90.0), View()) is skel  # the ideal tracker never changes anything


@pytest.mark.parametrize("yaw", [75.0, 90.0, -90.0, 110.0])
def test_side_on_the_far_shoulder_is_inferred_as_if_facing(yaw):
    skel = _turned(yaw)
    seen = track(skel, np.deg2rad(yaw), View(tracker="occluding"))
    d = np.linalg.norm(skel[0, [J["left_shoulder"], J["right_shoulder"]]], axis=1)
    far, near = (
        (J["left_shoulder"], J["right_shoulder"])
        if d[0] > d[1]
        else (J["right_shoulder"], J["left_shoulder"])
    )
    assert np.array_equal(seen[0, near], skel[0, near])
    torso = skel[0, J["torso"]]
    want = skel[0, near].copy()
    want[0] = 2 * torso[0] - want[0]  # mirrored across the torso, in the camera's x
    np.testing.assert_allclose(seen[0, far], want)
    # the reported shoulder line runs across the image: the body frame sees no turn at all
    rel = skel[:, J["right_hand"]] - skel[:, J["torso"]]
    turned = to_body_frame(rel, seen[:, J["left_shoulder"]], seen[:, J["right_shoulder"]])
    assert np.allclose(np.abs(turned), np.abs(rel))
    others = [i for i in range(len(OPENNI_JOINTS)) if i != far]
    assert np.array_equal(seen[0, others], skel[0, others])


def test_from_behind_left_and_right_trade_places():
    skel = _turned(180.0)
    seen = track(skel, np.pi, View(tracker="occluding"))
    np.testing.assert_array_equal(seen[0, J["right_hand"]], skel[0, J["left_hand"]])
    np.testing.assert_array_equal(seen[0, J["left_shoulder"]], skel[0, J["right_shoulder"]])
    np.testing.assert_array_equal(seen[0, J["torso"]], skel[0, J["torso"]])


def test_a_gesture_seen_from_behind_follows_the_resting_hand():
    """The person's right hand taps; from behind the occluding tracker follows their left, which rests: the
    features barely move (the ideal tracker's move tens of centimetres)."""
    kw = {"view": View(yaw_deg=180.0, tracker="occluding"), **CLEAN}
    seen = synthesize_gesture("tap", np.random.default_rng(2), **kw).features()
    ideal = synthesize_gesture("tap", np.random.default_rng(2), view=View(yaw_deg=180.0), **CLEAN).features()
    assert np.ptp(seen, axis=0).max() < 0.05 < np.ptp(ideal, axis=0).max()


def test_side_on_the_body_frame_no_longer_undoes_the_turn():
    """Ideal tracker: the body frame of a person turned by 90° equals the front view's (tested in
    test_body_frame); occluding: it does not, and equals the torso-frame features seen side-on."""
    rng = lambda: np.random.default_rng(3)  # noqa: E731
    front = synthesize_gesture("grasp", rng(), view=View(yaw_deg=0.0, body_frame=True), **CLEAN).features()
    occ = View(yaw_deg=90.0, body_frame=True, tracker="occluding")
    body = synthesize_gesture("grasp", rng(), view=occ, **CLEAN).features()
    torso = synthesize_gesture(
        "grasp", rng(), view=View(yaw_deg=90.0, tracker="occluding"), **CLEAN
    ).features()
    assert not np.allclose(body, front, atol=0.1)
    np.testing.assert_allclose(body, torso, atol=1e-9)


@pytest.mark.parametrize("yaw", [30.0, 90.0, 150.0, None])
@pytest.mark.parametrize("body_frame", [False, True])
def test_batch_path_equals_one_at_a_time(yaw, body_frame):
    view = View(yaw_deg=yaw, tracker="occluding", body_frame=body_frame, variety=1.0)
    acts = ["grasp", "tap", "touch", "push"] * 3
    rngs = lambda: [np.random.default_rng([9, i]) for i in range(len(acts))]  # noqa: E731
    fast = gesture_features(acts, rngs(), view=view, noise=0.02)
    for i, (a, r) in enumerate(zip(acts, rngs(), strict=True)):
        assert np.array_equal(fast.features[i], synthesize_gesture(a, r, view=view, noise=0.02).features())


def test_bad_trackers_are_one_line():
    with pytest.raises(DataError, match="unknown tracker 'kinect'; allowed: ideal, occluding"):
        View(tracker="kinect")
    with pytest.raises(DataError, match="robot senses its own joints"):
        View(performer="robot", tracker="occluding")
    assert "occluding tracker" in View(tracker="occluding").describe()
