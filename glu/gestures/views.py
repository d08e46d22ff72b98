"""How the robot's camera sees a person (or the robot itself): a :class:`View` of a synthetic gesture.

The synthetic generator (:mod:`glu.gestures.synthetic`) draws each person in full and then applies the
view: their turn about the vertical, a mirror image, the posture, the body size, how far their arm length
and movement style differ from the standard ones, how the features are computed from the skeleton, and the
skeleton tracker that reports the joints.

**The tracker.** The ``ideal`` tracker reports every joint where it is, whichever way the person faces the
camera. A real skeleton tracker (a depth camera's, fitted to a body it assumes faces it) does not:
:func:`track` gives the ``occluding`` tracker's report of a skeleton,

* turned by more than :data:`OCCLUSION_DEG` (side-on), the far shoulder is hidden behind the body: the
  tracker infers it as if the person faced the camera, mirroring the near shoulder across the torso in the
  camera's frame (so the shoulder line it reports runs across the image, shortened by the cosine of the
  turn, and says nothing of the turn);
* turned by more than :data:`SWAP_DEG` (seen from behind), it takes the back for the front: every left
  joint is reported as the right one and vice versa, so the "right hand" it follows is the person's left.

Everything else (the near shoulder, the hands, the torso) it reports where it is. The turn is the
person's own (the view's ``yaw_deg``, or the random ± 10° of the recordings); the robot's own movements are
sensed by its joints, never by a tracker.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from glu.errors import DataError
from glu.gestures.features import OPENNI_JOINTS

POSTURES: tuple[str, ...] = ("standing", "seated")
PERFORMERS: tuple[str, ...] = ("human", "robot")
"""Who moves: a person seen by the robot's camera, or the robot itself (its end effector, its body frame)."""
TRACKERS: tuple[str, ...] = ("ideal", "occluding")
"""How the skeleton tracker reports a person turned away from the camera (module docstring, :func:`track`)."""
OCCLUSION_DEG = 60.0
"""Turned further than this (degrees, either way), the occluding tracker loses the far shoulder."""
SWAP_DEG = 120.0
"""Turned further than this (seen from behind), the occluding tracker swaps left and right."""


@dataclass(frozen=True)
class View:
    """How the robot's camera sees the person (all fields optional; the defaults are the generator's).

    Attributes
    ----------
    yaw_deg : the person's turn about the vertical axis relative to the camera, degrees (0 = facing it,
        90 = side-on); ``None`` draws a random turn in ± 10°, as in the real recordings
    mirror : the movement mirrored across the person's sagittal plane (x → −x relative to the torso):
        the same action made with the other hand, or seen from in front instead of from behind
    posture : ``"standing"`` (at a table) or ``"seated"`` (hand resting on the thigh, table higher and
        further relative to the torso)
    size : body size factor (1 = shoulders 0.33 m apart; for the robot, its own body); ``None`` draws
        one in 0.85–1.15 for a person, 1 for the robot
    normalise_body : features divided by the body's measured shoulder and neck–torso distances (the 2013
        system); False: by the constants 0.33 m and 0.23 m whatever the body, as the 2017 logs were
        computed, so body size (and the robot's smaller body) stays in the features
    performer : ``"human"`` (a person seen by the robot's camera) or ``"robot"`` (the robot's own
        movement, its end effector in its body frame; :mod:`glu.gestures.robot`)
    variety : how far each person's arm length and movement style differ from the generator's standard
        ones (0: not at all; see the module docstring)
    body_frame : features in the shoulder line's frame instead of the torso's
    tracker : the skeleton tracker, ``"ideal"`` or ``"occluding"`` (:data:`TRACKERS`, :func:`track`)
    """

    yaw_deg: float | None = None
    mirror: bool = False
    posture: str = "standing"
    size: float | None = None
    normalise_body: bool = True
    performer: str = "human"
    variety: float = 0.0
    body_frame: bool = False
    tracker: str = "ideal"

    def __post_init__(self) -> None:
        if self.yaw_deg is not None and not np.isfinite(self.yaw_deg):
            raise DataError(f"view yaw_deg={self.yaw_deg} is not a finite angle in degrees")
        if self.posture not in POSTURES:
            raise DataError(f"unknown posture {self.posture!r}; allowed: {', '.join(POSTURES)}")
        if self.size is not None and not 0.3 <= self.size <= 3.0:
            raise DataError(f"view size={self.size} is outside 0.3–3 (1 = shoulders 0.33 m apart)")
        if self.performer not in PERFORMERS:
            raise DataError(f"unknown performer {self.performer!r}; allowed: {', '.join(PERFORMERS)}")
        if self.performer == "robot" and self.posture != "standing":
            raise DataError("the robot has one posture: give posture only for a human performer")
        if not (isinstance(self.variety, int | float) and 0 <= self.variety <= 3):
            raise DataError(f"view variety={self.variety!r}: a number from 0 (the standard people) to 3")
        if self.tracker not in TRACKERS:
            raise DataError(f"unknown tracker {self.tracker!r}; allowed: {', '.join(TRACKERS)}")
        if self.performer == "robot" and self.tracker != "ideal":
            raise DataError("the robot senses its own joints: give a tracker only for a human performer")

    def describe(self) -> str:
        """One line, e.g. ``human, standing, yaw 90°, mirrored, size 1.2``."""
        human = self.performer == "human"
        yaw = "yaw ±10°" if self.yaw_deg is None and human else f"yaw {self.yaw_deg or 0:g}°"
        parts = [
            *([self.performer, self.posture] if human else ["robot"]),
            yaw,
            "mirrored" * self.mirror,
            f"size {self.size:g}" if self.size else "",
            "fixed scale" * (not self.normalise_body),
            f"people varied ×{self.variety:g}" if self.variety else "",
            "body frame" * self.body_frame,
            "occluding tracker" * (self.tracker == "occluding"),
        ]
        return ", ".join(p for p in parts if p)


DEFAULT_VIEW = View()


_PAIRS = [
    (OPENNI_JOINTS.index(j), OPENNI_JOINTS.index("right_" + j.removeprefix("left_")))
    for j in OPENNI_JOINTS
    if j.startswith("left_")
]
_LS, _RS, _TORSO = (OPENNI_JOINTS.index(j) for j in ("left_shoulder", "right_shoulder", "torso"))


def tracker_state(yaw_deg: float) -> str:
    """What the occluding tracker makes of a person turned by ``yaw_deg``: ``"sees all"``, ``"far shoulder
    lost"`` (beyond :data:`OCCLUSION_DEG`) or ``"left and right swapped"`` (beyond :data:`SWAP_DEG`)."""
    turn = abs((float(yaw_deg) + 180.0) % 360.0 - 180.0)
    if turn > SWAP_DEG:
        return "left and right swapped"
    if turn > OCCLUSION_DEG:
        return "far shoulder lost"
    return "sees all"


def track(skeleton: np.ndarray, yaw_rad: float, view: View) -> np.ndarray:
    """The joints ``view``'s tracker reports for a skeleton, shape (n_frames, 15, 3) → the same.

    See the module docstring: beyond :data:`OCCLUSION_DEG` the far shoulder (the one further from the
    camera, frame by frame) is reported at the near one mirrored across the torso in the camera's x; beyond
    :data:`SWAP_DEG` every left and right joint trade places.

    Parameters
    ----------
    skeleton : the true joints in the camera's frame (:data:`~glu.gestures.features.OPENNI_JOINTS` order;
        the camera at the origin)
    yaw_rad : the person's turn relative to the camera, radians
    view : the view (its ``tracker``; an ``ideal`` tracker returns ``skeleton`` itself)
    """
    if view.tracker == "ideal":
        return skeleton
    state = tracker_state(np.rad2deg(yaw_rad))
    if state == "sees all":
        return skeleton
    out = np.array(skeleton, dtype=float, copy=True)
    if state == "left and right swapped":
        for left, right in _PAIRS:
            out[:, [left, right]] = skeleton[:, [right, left]]
        return out
    far_left = np.linalg.norm(skeleton[:, _LS], axis=1) > np.linalg.norm(skeleton[:, _RS], axis=1)
    near = np.where(far_left[:, None], skeleton[:, _RS], skeleton[:, _LS])
    torso = skeleton[:, _TORSO]
    inferred = near.copy()
    inferred[:, 0] = 2 * torso[:, 0] - near[:, 0]
    out[far_left, _LS] = inferred[far_left]
    out[~far_left, _RS] = inferred[~far_left]
    return out
