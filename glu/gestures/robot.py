"""The robot's own movements: end-effector trajectories of an iCub-like robot's grasp, tap and touch.

The robot learns its affordances from its own actions (docs/method.md §1), so its own movements are the first
gesture data it has. This module draws them in the robot's body frame, the way its arm controller makes
them: a Cartesian reach through waypoints, each segment a straight minimum-jerk move that starts and ends
at rest (as iCub's Cartesian controller does), with a short hold at contact:

* **grasp** — from home to above the object, down to it, close the hand (a hold), lift it about 12 cm,
  back home;
* **tap** — from home to the right of the object, a fast strike leftwards across it, lift off, home;
* **touch** — from home to above the object, down to contact (a hold), up again, home.

The body frame is the robot's, with glu's axes (x right, y up, z back, origin at the chest, as the torso
of a person's skeleton; iCub's own root frame has x back, y right, z up at the waist). The body has iCub-like
proportions, about two thirds of an adult's: shoulders 0.22 m apart, neck 0.15 m above the chest, an arm
that reaches about 0.3 m; the hand's home is in front of the belly with the forearm forward (not hanging
beside the hip like a person's). Variability is a robot's: the object's position (± 3 cm), the trajectory
times of the controller (segments of 0.6–1.2 s), a little encoder noise (:data:`ROBOT_NOISE`), no tracking
spikes or dropouts. These are iCub-like values chosen for the study of the correspondence problem, not
measured on a robot.

:func:`robot_hand_path` returns the hand path relative to the chest; :mod:`glu.gestures.synthetic` turns
it into a skeleton sequence (``View(performer="robot")``) so the gesture features are computed exactly
as for a person.
"""

from __future__ import annotations

import numpy as np

from glu.errors import DataError

ROBOT_ACTIONS: tuple[str, ...] = ("grasp", "tap", "touch")
"""The robot's own actions (the BN's Action values)."""
ROBOT_NOISE = 0.002
"""Metres: standard deviation of the forward-kinematics noise (encoders, not a camera)."""
ROBOT_SHOULDERS = 0.22
"""Metres between the robot's shoulders."""
ROBOT_NECK = 0.15
"""Metres from the robot's chest (the skeleton's torso) up to its neck."""

ROBOT_BODY: dict[str, tuple[float, float, float]] = {
    "head": (0.0, 0.27, 0.0),
    "neck": (0.0, ROBOT_NECK, 0.0),
    "left_shoulder": (-ROBOT_SHOULDERS / 2, 0.13, 0.0),
    "right_shoulder": (ROBOT_SHOULDERS / 2, 0.13, 0.0),
    "left_elbow": (-0.13, -0.02, 0.0),
    "left_hand": (-0.12, -0.1, -0.14),
    "torso": (0.0, 0.0, 0.0),
    "left_hip": (-0.07, -0.2, 0.0),
    "right_hip": (0.07, -0.2, 0.0),
    "left_knee": (-0.07, -0.45, -0.02),
    "right_knee": (0.07, -0.45, -0.02),
    "left_foot": (-0.07, -0.7, 0.0),
    "right_foot": (0.07, -0.7, 0.0),
}
"""Joints of the robot relative to its chest, metres (x right, y up, z back); the right arm is the path."""
ROBOT_HOME = np.array([0.12, -0.1, -0.14])
"""The right hand at home: in front of the belly, forearm forward."""
ROBOT_OBJECT = np.array([0.03, -0.16, -0.3])
"""The object on the table in front of the robot, relative to its chest."""
ROBOT_FRAME_RATE = 30.0
"""Frames a second (the rate of the person's skeleton, so both are compared frame for frame)."""

# Waypoints: (offset from the object, or None for home; hold at the waypoint, s).
_WAYPOINTS: dict[str, list[tuple[tuple[float, float, float] | None, float]]] = {
    "grasp": [
        (None, 0.0),
        ((0.0, 0.08, 0.03), 0.0),
        ((0.0, 0.01, 0.0), 0.4),
        ((0.0, 0.12, 0.0), 0.1),
        (None, 0.0),
    ],
    "tap": [
        (None, 0.0),
        ((0.1, 0.02, 0.0), 0.0),
        ((-0.08, 0.02, 0.0), 0.0),
        ((-0.05, 0.07, 0.05), 0.0),
        (None, 0.0),
    ],
    "touch": [
        (None, 0.0),
        ((0.0, 0.07, 0.0), 0.0),
        ((0.0, 0.015, 0.0), 0.3),
        ((0.0, 0.07, 0.0), 0.0),
        (None, 0.0),
    ],
}
_FAST = {("tap", 2)}
"""Segments the controller runs faster (the strike of a tap): (action, index of the segment's end)."""


def _min_jerk(a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """A straight minimum-jerk move from a to b in n frames (both ends included, at rest), shape (n, 3)."""
    s = np.linspace(0.0, 1.0, n)[:, None]
    return a + (b - a) * (10 * s**3 - 15 * s**4 + 6 * s**5)


def robot_hand_path(action: str, rng: np.random.Generator, size: float = 1.0) -> np.ndarray:
    """The robot's right hand relative to its chest, metres, shape (n_frames, 3), for one ``action``.

    Parameters
    ----------
    action : one of :data:`ROBOT_ACTIONS`
    rng : the random generator (object position, segment durations)
    size : the robot's size factor (1 = the body of :data:`ROBOT_BODY`)
    """
    if action not in _WAYPOINTS:
        raise DataError(f"the robot has no action {action!r}; allowed: {', '.join(ROBOT_ACTIONS)}")
    obj = ROBOT_OBJECT + rng.uniform(-0.03, 0.03, size=3) * np.array([1.0, 0.3, 1.0])
    home = ROBOT_HOME + rng.normal(0.0, 0.003, size=3)
    points = [(home if off is None else obj + np.asarray(off), hold) for off, hold in _WAYPOINTS[action]]
    parts = [points[0][0][None]]
    for k in range(1, len(points)):
        duration = rng.uniform(0.6, 1.2) * (0.4 if (action, k) in _FAST else 1.0)
        n = max(int(round(duration * ROBOT_FRAME_RATE)), 4)
        parts.append(_min_jerk(points[k - 1][0], points[k][0], n + 1)[1:])
        hold = int(round(points[k][1] * ROBOT_FRAME_RATE))
        parts.append(np.repeat(points[k][0][None], hold, 0))  # (0, 3) without a hold
    return np.concatenate(parts) * size
