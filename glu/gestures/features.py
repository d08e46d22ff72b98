"""Gesture features: a skeleton's right hand in the torso frame, normalised by body size (docs/method.md
§4.2).

The features of the original system (Saponaro et al., CR-HRI 2013; the ``humanHandProcessor`` of
GLU 2017) are, per frame, the right hand minus the torso,

* **x** — horizontal, positive to the person's right (the person's point of view),
* **y** — vertical, positive upwards,
* **z** — orthogonal to the torso, positive towards the person's back (so a reach forward makes z < 0),

with x and z divided by a horizontal factor, the mean distance between the shoulders, and y by a
vertical factor, the mean distance between neck and torso, both averaged over the middle part of the
sequence (frames 45–55 %). When no skeleton is available the original used the constants 0.33 and 0.23
(metres, measured on the 2012 training data). Features are therefore unitless: one unit is about a
shoulder width horizontally and a neck–torso distance vertically. No rotation is applied: the skeleton
must be in the person's frame above (the sensor's frame for a person facing it, as in the recordings).

**The body frame** (``frame="body"``, :func:`to_body_frame`) is an alternative that glu adds: the hand
minus the torso is turned about the vertical into the frame the shoulder line defines, so that x runs from
the left shoulder to the right one and z towards the back, whichever way the person faces the camera. The
shoulder line is the running mean of right shoulder − left shoulder over the frames so far (online, and
averaging out the joints' noise). Unlike the movement-heading rotation of :mod:`glu.gestures.invariants`,
it keeps the movement's direction relative to the body. It needs the shoulders, which the published hand
logs do not hold.

The YARP logs of 2017 hold these features already, but computed from millimetres with the metre
constants, i.e. 1000 × the units of the 2013 models; the original scripts divide them by 1000
(:data:`LOG_SCALE`, :func:`log_features`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from glu.data.skeleton import OPENNI_JOINTS, SKELETON_JOINTS
from glu.errors import DataError
from glu.gestures.trajectories import Trajectory

if TYPE_CHECKING:  # the arrays of a table, as the data module reads it
    from glu.data.trajectory_files import TrajectoryTable

AXES: tuple[str, str, str] = ("x", "y", "z")
FEATURES_DESCRIPTION = (
    "right hand minus torso; x (right) and z (back) / mean shoulder distance, y (up) / mean neck-torso "
    "distance (docs/method.md §4.2); YARP hand logs / 1000"
)
"""What the gesture models expect, recorded in every recogniser file."""
LOG_SCALE = 1000.0
"""The logged features are ``LOG_SCALE`` × the units of the original models."""
HORIZONTAL_FALLBACK = 0.33
"""Metres: the horizontal factor (shoulder distance) used when the skeleton has no shoulders."""
VERTICAL_FALLBACK = 0.23
"""Metres: the vertical factor (neck–torso distance) used when the skeleton has no neck or torso."""
MIDDLE: tuple[float, float] = (0.45, 0.55)
"""The part of the sequence over which the normalisation factors are averaged."""


class Normalisation(NamedTuple):
    """The body-size factors of a sequence, in the skeleton's units, and whether each is a fallback."""

    horizontal: float
    vertical: float
    horizontal_fallback: bool
    vertical_fallback: bool


def middle_frames(n_frames: int, middle: tuple[float, float] = MIDDLE) -> slice:
    """The frames ``i`` (0-based) with ``middle[0]·n ≤ i < middle[1]·n``; at least the middle frame.

    For 100 frames this is frames 45 … 54 (0-based), i.e. the 46th to the 55th frame.
    """
    if n_frames < 1:
        raise DataError("a sequence needs at least one frame")
    lo = math.ceil(round(middle[0] * n_frames, 9))  # round: 0.55 * 100 is 55.000000000000007
    hi = math.ceil(round(middle[1] * n_frames, 9))
    if hi <= lo:
        lo = min(int(middle[0] * n_frames), n_frames - 1)
        hi = lo + 1
    return slice(lo, hi)


def _joint(skeleton: np.ndarray, joints: tuple[str, ...], name: str) -> np.ndarray:
    try:
        return skeleton[:, joints.index(name), :]
    except ValueError:
        raise DataError(f"the skeleton has no joint {name!r}; joints: {', '.join(joints)}") from None


def _check_skeleton(skeleton: np.ndarray, joints: tuple[str, ...]) -> np.ndarray:
    skeleton = np.asarray(skeleton, dtype=float)
    if skeleton.ndim != 3 or skeleton.shape[1:] != (len(joints), 3) or len(skeleton) == 0:
        raise DataError(
            f"a skeleton must have shape (n_frames ≥ 1, {len(joints)}, 3) for the joints "
            f"{', '.join(joints)}; got {skeleton.shape}"
        )
    return skeleton


def normalisation_factors(
    skeleton: np.ndarray,
    joints: tuple[str, ...] = OPENNI_JOINTS,
    fallback: tuple[float, float] = (HORIZONTAL_FALLBACK, VERTICAL_FALLBACK),
) -> Normalisation:
    """Mean shoulder distance and mean neck–torso distance over the middle frames of a skeleton
    (:data:`MIDDLE`).

    Parameters
    ----------
    skeleton : array, shape (n_frames, n_joints, 3); missing joints are NaN
    joints : the joint names along axis 1
    fallback : (horizontal, vertical) in the skeleton's units (the defaults are metres), used for a
        factor whose joints are missing in every middle frame
    """
    skeleton = _check_skeleton(skeleton, joints)
    mid = middle_frames(len(skeleton))

    def mean_distance(a: str, b: str) -> float:
        d = np.linalg.norm(_joint(skeleton, joints, a)[mid] - _joint(skeleton, joints, b)[mid], axis=1)
        d = d[np.isfinite(d) & (d > 0)]
        return float(d.mean()) if len(d) else math.nan

    h = mean_distance("left_shoulder", "right_shoulder")
    v = mean_distance("neck", "torso")
    return Normalisation(
        horizontal=h if math.isfinite(h) else fallback[0],
        vertical=v if math.isfinite(v) else fallback[1],
        horizontal_fallback=not math.isfinite(h),
        vertical_fallback=not math.isfinite(v),
    )


FRAMES: tuple[str, ...] = ("torso", "body")
"""The frames the features can be computed in: the skeleton's own (the originals'), or the shoulder line's."""


def to_body_frame(rel: np.ndarray, left_shoulder: np.ndarray, right_shoulder: np.ndarray) -> np.ndarray:
    """Hand-minus-torso vectors turned into the body frame of the shoulder line, shape (T, 3) → (T, 3).

    Frame t uses the running mean ``m_t`` of ``right_shoulder − left_shoulder`` over frames 1 … t
    (horizontal part, frames with a missing shoulder skipped; until one is seen, no turn): with
    ``u = m_t / |m_t|``, ``x' = u_x x + u_z z`` and ``z' = −u_z x + u_x z`` (y unchanged), so a person
    facing the camera (shoulders along +x) keeps their features, and one turned by ψ gets them back.
    """
    line = (
        np.asarray(right_shoulder, dtype=float)[:, [0, 2]] - np.asarray(left_shoulder, dtype=float)[:, [0, 2]]
    )
    ok = np.isfinite(line).all(axis=1)
    total = np.cumsum(np.where(ok[:, None], line, 0.0), axis=0)
    norm = np.hypot(total[:, 0], total[:, 1])
    safe = norm > 0
    ux = np.where(safe, total[:, 0] / np.where(safe, norm, 1.0), 1.0)
    uz = np.where(safe, total[:, 1] / np.where(safe, norm, 1.0), 0.0)
    rel = np.asarray(rel, dtype=float)
    out = rel.copy()
    out[:, 0] = ux * rel[:, 0] + uz * rel[:, 2]
    out[:, 2] = -uz * rel[:, 0] + ux * rel[:, 2]
    return out


def skeleton_features(
    skeleton: np.ndarray,
    joints: tuple[str, ...] = OPENNI_JOINTS,
    measure: bool = True,
    frame: str = "torso",
) -> tuple[np.ndarray, Normalisation]:
    """The original gesture features of a skeleton sequence (docs/method.md §4.2).

    Parameters
    ----------
    skeleton : array, shape (n_frames, n_joints, 3), in the person's frame (x right, y up, z back);
        frames where the hand or the torso is missing (NaN) give NaN features
    joints : the joint names along axis 1
    measure : divide by the body's measured factors (:func:`normalisation_factors`, the 2013 system);
        False: by the fallback constants whatever the body, as the 2017 logs were computed (body size then
        stays in the features)
    frame : ``"torso"`` (the skeleton's frame, the originals') or ``"body"`` (turned into the shoulder
        line's frame, :func:`to_body_frame`)

    Returns
    -------
    features : array, shape (n_frames, 3) —
        ``((hand - torso)_x / h, (hand - torso)_y / v, (hand - torso)_z / h)``
    normalisation : the factors ``h`` and ``v`` used
    """
    skeleton = _check_skeleton(skeleton, joints)
    if measure:
        norm = normalisation_factors(skeleton, joints)
    else:
        norm = Normalisation(HORIZONTAL_FALLBACK, VERTICAL_FALLBACK, True, True)
    if frame not in FRAMES:
        raise DataError(f"unknown feature frame {frame!r}; allowed: {', '.join(FRAMES)}")
    rel = _joint(skeleton, joints, "right_hand") - _joint(skeleton, joints, "torso")
    if frame == "body":
        rel = to_body_frame(
            rel, _joint(skeleton, joints, "left_shoulder"), _joint(skeleton, joints, "right_shoulder")
        )
    scale = np.array([norm.horizontal, norm.vertical, norm.horizontal])
    return rel / scale, norm


def log_features(xyz_logged: np.ndarray) -> np.ndarray:
    """The features of a YARP hand log in the units of the original models: the logged values / 1000.

    ``xyz_logged`` has shape (n_frames, 3); so has the result.
    """
    return np.asarray(xyz_logged, dtype=float) / LOG_SCALE


BODY_SIZE_RANGE = (0.01, 10.0)
"""A body size (horizontal or vertical, metres) glu accepts: smaller ones turn coordinates into infinities."""


def table_features(table: TrajectoryTable, body: tuple[float, float] | None = None) -> Trajectory:
    """The features of a recording read from a CSV/TSV/NPY table (:mod:`glu.data.trajectory_files`), as a
    trajectory (its arrays only: no file is read here).

    A hand table (``t, x, y, z`` in metres) is divided by ``body`` = (horizontal, vertical) body size in
    metres (default: the originals' fallback constants); a skeleton table gets :func:`skeleton_features`.
    """
    if table.kind == "hand":
        h, v = body or (HORIZONTAL_FALLBACK, VERTICAL_FALLBACK)
        if not (
            BODY_SIZE_RANGE[0] <= h < BODY_SIZE_RANGE[1] and BODY_SIZE_RANGE[0] <= v < BODY_SIZE_RANGE[1]
        ):
            raise DataError(
                f"body size ({h:g}, {v:g}) m: both must be between {BODY_SIZE_RANGE[0]:g} and "
                f"{BODY_SIZE_RANGE[1]:g} m (a person's shoulder width and neck-torso length)"
            )
        xyz = table.hand / np.array([h, v, h])
    else:
        names = SKELETON_JOINTS
        skeleton = np.stack([table.joints.get(j, np.full((len(table.t), 3), np.nan)) for j in names], axis=1)
        xyz, _ = skeleton_features(skeleton, joints=names)
    return Trajectory.recorded(xyz, table.t, table.source)
