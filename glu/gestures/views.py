"""How the robot's camera sees a person (or the robot itself): a :class:`View` of a synthetic gesture.

The synthetic generator (:mod:`glu.gestures.synthetic`) draws each person in full and then applies the
view: their turn about the vertical, a mirror image, the posture, the body size, how far their arm length
and movement style differ from the standard ones, and how the features are computed from the skeleton.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from glu.errors import DataError

POSTURES: tuple[str, ...] = ("standing", "seated")
PERFORMERS: tuple[str, ...] = ("human", "robot")
"""Who moves: a person seen by the robot's camera, or the robot itself (its end effector, its body frame)."""


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
    """

    yaw_deg: float | None = None
    mirror: bool = False
    posture: str = "standing"
    size: float | None = None
    normalise_body: bool = True
    performer: str = "human"
    variety: float = 0.0
    body_frame: bool = False

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
        ]
        return ", ".join(p for p in parts if p)


DEFAULT_VIEW = View()
