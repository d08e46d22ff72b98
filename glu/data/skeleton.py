"""The skeleton's joints: their names, as the recordings and glu's features know them.

Shared by the file formats (:mod:`glu.data.trajectory_files` reads skeleton tables by these names) and the
features (:mod:`glu.gestures.features` takes skeletons whose joints come in this order); a module of names
only, so that neither needs the other.
"""

from __future__ import annotations

SKELETON_JOINTS: tuple[str, ...] = ("torso", "right_hand", "left_shoulder", "right_shoulder", "neck")
"""The joints glu uses from a skeleton table (torso and right_hand are required)."""
OPENNI_JOINTS: tuple[str, ...] = (
    "head",
    "neck",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_hand",
    "right_hand",
    "torso",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_foot",
    "right_foot",
)
"""The 15 joints of the OpenNI skeleton, in the order of the YARP OpenNI2 driver."""
