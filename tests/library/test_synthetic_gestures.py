"""The synthetic gesture generator: seeded, any number of sequences, real-world variability as skeletons."""

from __future__ import annotations

import numpy as np
import pytest

from glu.errors import DataError
from glu.gestures.features import OPENNI_JOINTS, skeleton_features
from glu.gestures.synthetic import (
    GESTURES,
    View,
    synthesize_gesture,
    synthesize_gestures,
    synthesize_recording,
)
from glu.gestures.trajectories import repair


def test_same_seed_same_sequences_and_prefix_stability():
    a = synthesize_gestures(9, seed=11)
    b = synthesize_gestures(9, seed=11)
    c = synthesize_gestures(4, seed=11)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.skeleton, y.skeleton)
        np.testing.assert_array_equal(x.t, y.t)
    for x, y in zip(a[:4], c, strict=True):
        np.testing.assert_array_equal(x.skeleton, y.skeleton)
    d = synthesize_gestures(9, seed=12)
    assert not np.array_equal(a[0].skeleton, d[0].skeleton)


def test_actions_in_turn_shapes_and_timing():
    gs = synthesize_gestures(10, seed=0)
    assert [g.action for g in gs] == [GESTURES[i % 4] for i in range(10)]
    for g in gs:
        assert g.skeleton.ndim == 3 and g.skeleton.shape[1:] == (15, 3)
        assert len(g.t) == len(g.skeleton) and np.all(np.diff(g.t) > 0)
        assert 2.4 < g.t[-1] - g.t[0] < 6.1  # 2.5–5 s of movement, 3–15 still frames before and after
    assert synthesize_gestures(0) == []


def test_variability_is_present():
    gs = synthesize_gestures(40, seed=1, dropout_rate=1.0)
    sizes = [g.size for g in gs]
    assert min(sizes) < 0.9 and max(sizes) > 1.1
    lengths = [len(g.t) for g in gs]
    assert max(lengths) - min(lengths) > 20
    # every sequence lost a run of frames: its largest time step is well above the frame period
    assert all(np.diff(g.t).max() > 3 / 30 for g in gs)
    torsos = np.array([g.skeleton[0, 8] for g in gs])
    assert torsos.std(axis=0).min() > 0.05  # people stand in different places


def test_noise_free_gestures_are_smooth_and_noise_adds_spikes():
    (clean,) = synthesize_gestures(1, seed=2, noise=0.0, spike_rate=0.0, dropout_rate=0.0)
    f, _ = skeleton_features(clean.skeleton)
    assert np.abs(np.diff(f, 2, axis=0)).max() < 0.05
    (spiky,) = synthesize_gestures(1, seed=2, noise=0.0, spike_rate=0.2, dropout_rate=0.0)
    assert any(e.kind == "spike" for e in repair(spiky.trajectory()).events)


def test_gestures_differ_where_they_should():
    gs = synthesize_gestures(40, seed=3, noise=0.0, spike_rate=0.0, dropout_rate=0.0)
    feats = {a: [skeleton_features(g.skeleton)[0] for g in gs if g.action == a] for a in GESTURES}
    # a tap strikes laterally: its x range is the largest; a reach always goes forward (z < rest)
    x_range = {a: np.mean([f[:, 0].max() - f[:, 0].min() for f in fs]) for a, fs in feats.items()}
    assert max(x_range, key=x_range.get) == "tap"
    for fs in feats.values():
        for f in fs:
            assert f[:, 2].min() < f[0, 2] - 1.0


def test_recording_has_known_segments():
    rec = synthesize_recording("grasp", 3, seed=0)
    assert len(rec.segments) == 3
    assert all(a < b for a, b in rec.segments)
    assert all(rec.segments[i][1] < rec.segments[i + 1][0] for i in range(2))
    assert rec.segments[-1][1] < len(rec.t)


def test_bad_arguments():
    with pytest.raises(DataError, match="unknown action"):
        synthesize_gestures(3, actions=("wave",))
    with pytest.raises(DataError, match="noise"):
        synthesize_gestures(3, noise=-1)
    with pytest.raises(DataError):
        synthesize_recording("grasp", 0)
    with pytest.raises(DataError, match="number of sequences -1 is negative"):
        synthesize_gestures(-1)
    with pytest.raises(DataError, match="unknown action 'wave'; allowed: grasp, tap, touch, push"):
        synthesize_recording("wave", 2)
    for placements in ([(1, 20)], [(5, 10)], [(5, 30), (30, 60)], [(40, 60), (5, 30)]):
        with pytest.raises(DataError, match="must be in order, apart, after frame 1, ≥ 10 frames each"):
            synthesize_recording("tap", 2, placements=placements)
    with pytest.raises(DataError, match=r"n_frames=50 is shorter than the last placement \(60\)"):
        synthesize_recording("tap", 2, placements=[(5, 30), (40, 60)], n_frames=50)


# ---------------------------------------------------------------- views
def _clean(view, seed=3, action="tap"):
    rng = np.random.default_rng(seed)
    return synthesize_gesture(action, rng, noise=0.0, spike_rate=0.0, dropout_rate=0.0, view=view)


def _rot_y(deg):
    c, s = np.cos(np.deg2rad(deg)), np.sin(np.deg2rad(deg))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def test_no_view_and_the_default_view_draw_the_same_sequences():
    a, b = _clean(None), _clean(View())
    np.testing.assert_array_equal(a.skeleton, b.skeleton)
    np.testing.assert_array_equal(a.t, b.t)


@pytest.mark.parametrize("yaw", [30.0, 90.0, 180.0])
def test_a_turned_person_gives_the_rotated_features(yaw):
    """Features are torso-relative and x, z share one factor, so a turn about y rotates them exactly."""
    front, turned = _clean(View(yaw_deg=0.0)), _clean(View(yaw_deg=yaw))
    np.testing.assert_allclose(turned.trajectory().xyz, front.trajectory().xyz @ _rot_y(yaw).T, atol=1e-12)


def test_a_mirrored_movement_negates_x_and_keeps_y_and_z():
    plain, mirrored = _clean(View(yaw_deg=0.0)), _clean(View(yaw_deg=0.0, mirror=True))
    np.testing.assert_allclose(mirrored.trajectory().xyz, plain.trajectory().xyz * [-1, 1, 1], atol=1e-12)


def test_seated_puts_the_hand_higher_and_the_table_further():
    standing, seated = _clean(View(posture="standing")), _clean(View(posture="seated"))
    ys, yt = standing.trajectory().xyz, seated.trajectory().xyz
    assert yt[:, 1].mean() > ys[:, 1].mean() + 0.2  # y is up, in units of the neck–torso distance
    assert yt[:, 2].min() < ys[:, 2].min() - 0.3  # z is towards the back: the table is further in front


def test_a_view_fixes_the_body_size():
    g = _clean(View(size=1.2))
    sk = g.skeleton
    ls, rs = OPENNI_JOINTS.index("left_shoulder"), OPENNI_JOINTS.index("right_shoulder")
    np.testing.assert_allclose(np.linalg.norm(sk[:, ls] - sk[:, rs], axis=1), 0.33 * 1.2, atol=1e-12)
    assert g.size == 1.2


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"posture": "lying"}, "unknown posture"),
        ({"yaw_deg": float("nan")}, "not a finite angle"),
        ({"size": 10.0}, "outside 0.3–3"),
    ],
)
def test_bad_views_are_refused(kwargs, message):
    with pytest.raises(DataError, match=message):
        View(**kwargs)


# ---------------------------------------------------------------- the robot's own movements
def _robot(action, seed=0, **view):
    rng = np.random.default_rng(seed)
    return synthesize_gesture(
        action, rng, noise=0.0, spike_rate=0.0, dropout_rate=0.0, view=View(performer="robot", **view)
    )


def test_the_robot_moves_in_its_own_body_frame():
    from glu.gestures.robot import ROBOT_HOME, ROBOT_NECK, ROBOT_SHOULDERS

    g = _robot("tap")
    sk = g.skeleton
    torso = sk[:, OPENNI_JOINTS.index("torso")]
    np.testing.assert_array_equal(torso, 0.0)  # no camera: the chest is the origin, no sway, no turn
    hand = sk[:, OPENNI_JOINTS.index("right_hand")]
    np.testing.assert_allclose(hand[0], ROBOT_HOME, atol=0.02)  # starts at home, in front of the belly
    assert hand[0, 2] < 0 and hand[:, 2].min() < hand[0, 2] - 0.1  # reaches forward to the object
    f = g.trajectory().xyz  # normalised by the robot's own body
    np.testing.assert_allclose(f, (hand - torso) / [ROBOT_SHOULDERS, ROBOT_NECK, ROBOT_SHOULDERS], atol=1e-12)
    fixed = _robot("tap", normalise_body=False).trajectory().xyz  # by a person's constants: a smaller body
    np.testing.assert_allclose(fixed, (hand - torso) / [0.33, 0.23, 0.33], atol=1e-12)


@pytest.mark.parametrize("action", ["grasp", "tap", "touch"])
def test_the_robot_reaches_through_waypoints_where_it_stops(action):
    """Approach, contact, retreat: straight minimum-jerk segments between 5 waypoints, each at rest."""
    hand = _robot(action).skeleton[:, OPENNI_JOINTS.index("right_hand")]
    speed = np.linalg.norm(np.diff(hand, axis=0), axis=1)  # metres per frame
    moving = np.flatnonzero(speed > 1e-9)
    slow = speed[moving[0] : moving[-1] + 1] < 2e-4  # below 6 mm/s inside the movement
    runs = int(slow[0]) + int(np.sum(slow[1:] & ~slow[:-1]))  # runs of (near) rest
    assert runs == 5  # leaving home, 3 waypoints, arriving home
    human = synthesize_gesture(action, np.random.default_rng(0), noise=0.0, spike_rate=0.0, dropout_rate=0.0)
    hs = np.linalg.norm(np.diff(human.skeleton[:, OPENNI_JOINTS.index("right_hand")], axis=0), axis=1)
    inside = hs[np.flatnonzero(hs > 1e-9)[0] : np.flatnonzero(hs > 1e-9)[-1] + 1]
    assert inside.min() > 2e-4  # a person's hand never stops mid-movement


def test_robot_views_are_checked():
    with pytest.raises(DataError, match="unknown action 'push' for a robot"):
        _robot("push")
    with pytest.raises(DataError, match="one posture"):
        View(performer="robot", posture="seated")
    with pytest.raises(DataError, match="unknown performer"):
        View(performer="dog")
    assert _robot("grasp", mirror=True).skeleton[0, OPENNI_JOINTS.index("right_hand"), 0] < 0  # its left arm
    assert View(performer="robot", yaw_deg=30.0).describe() == "robot, yaw 30°"


def test_the_robot_has_only_its_own_actions():
    from glu.gestures.robot import robot_hand_path

    with pytest.raises(DataError, match=r"^the robot has no action 'kick'; allowed: grasp, tap, touch$"):
        robot_hand_path("kick", np.random.default_rng(0))
