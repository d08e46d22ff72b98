r"""Your own gesture recordings: hand trajectories or skeletons from CSV, TSV or NumPy files.

Besides YARP hand logs (:mod:`glu.data.hand_logs`), glu reads a recording from a table, one frame a row:

* **the hand in the torso frame**, columns ``t, x, y, z``: ``t`` in seconds (strictly increasing), ``x y z``
  the right hand minus the torso in **metres**, x to the person's right, y up, z towards the person's back
  (a reach forward makes z < 0). glu divides x and z by a horizontal body size and y by a vertical one
  (default: the originals' 0.33 m and 0.23 m, docs/method.md §4.2) to get the models' features.
* **a skeleton**, columns ``t`` and ``<joint>_x, <joint>_y, <joint>_z`` for the joints ``torso``,
  ``right_hand``, and for the body size ``left_shoulder``, ``right_shoulder``, ``neck`` (others are
  ignored), in metres, in the person's frame as above; glu computes the features as the original system
  did (:func:`glu.gestures.features.skeleton_features`: body size from the middle of the sequence).

``.csv`` is comma-separated, ``.tsv`` tab-separated, both with a header line. ``.npy`` holds one array:
shape (T, 4) for ``t, x, y, z``, (T, 3) for ``x, y, z`` at 30 frames a second, or (T, 15, 3) for an OpenNI
skeleton at 30 frames a second (joints in :data:`glu.gestures.features.OPENNI_JOINTS` order).

>>> table = parse_trajectory_table("t,x,y,z\n0.0,0.1,-0.2,-0.3\n0.033,0.11,-0.2,-0.31\n", ",", "rec.csv")
>>> table.kind, table.hand.shape
('hand', (2, 3))
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import NamedTuple

import numpy as np

from glu.data.skeleton import OPENNI_JOINTS, SKELETON_JOINTS
from glu.errors import DataError
from glu.files import read_text

TABLE_SUFFIXES: dict[str, str] = {".csv": ",", ".tsv": "\t"}
"""Table files and their separators."""
ARRAY_SUFFIXES: tuple[str, ...] = (".npy",)
NPY_FRAME_RATE = 30.0
"""Frames a second assumed for ``.npy`` arrays without timestamps."""


class TrajectoryTable(NamedTuple):
    """A recording read from a table.

    Attributes
    ----------
    t : array, shape (n_frames,) — seconds, strictly increasing
    kind : ``"hand"`` (``hand`` holds the hand minus the torso) or ``"skeleton"`` (``joints`` holds them)
    hand : array, shape (n_frames, 3), metres, or None
    joints : joint name → array, shape (n_frames, 3), metres, or None
    source : the file name (for messages)
    """

    t: np.ndarray
    kind: str
    hand: np.ndarray | None
    joints: dict[str, np.ndarray] | None
    source: str


def is_trajectory_file(path: str | os.PathLike) -> bool:
    """True for the suffixes this module reads (``.csv``, ``.tsv``, ``.npy``)."""
    return Path(path).suffix.lower() in (*TABLE_SUFFIXES, *ARRAY_SUFFIXES)


def read_trajectory_table(path: str | os.PathLike) -> TrajectoryTable:
    """Read a CSV, TSV or NPY recording (a path :func:`is_trajectory_file` accepts; see the module docstring);
    :class:`DataError` naming the file."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in ARRAY_SUFFIXES:
        try:
            arr = np.load(path, allow_pickle=False)
        except FileNotFoundError:
            raise DataError(f"{path}: no such file") from None
        except (OSError, ValueError) as e:
            raise DataError(f"{path}: not a NumPy array file ({e})") from None
        arr = np.asarray(arr)
        if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
            raise DataError(
                f"{path}: an array of {arr.dtype} values; a trajectory is real numbers (t, x, y, z)"
            )
        return _from_array(arr, str(path))
    text = read_text(path, "trajectory table", encoding="utf-8-sig")
    return parse_trajectory_table(text, TABLE_SUFFIXES[suffix], str(path))


def parse_trajectory_table(text: str, sep: str, source: str = "<string>") -> TrajectoryTable:
    """Parse the text of a CSV/TSV recording with separator ``sep``."""
    import pandas as pd

    try:
        df = pd.read_csv(io.StringIO(text), sep=sep, dtype=float, skipinitialspace=True)
    except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        raise DataError(
            f"{source}: not a table of numbers with a header line ({e})".replace("\n", " ")
        ) from None
    df.columns = [str(c).strip() for c in df.columns]
    if "t" not in df.columns:
        raise DataError(f"{source}: no column 't' (seconds); columns: {', '.join(df.columns)}")
    t = df["t"].to_numpy()
    if {"x", "y", "z"} <= set(df.columns):
        hand = df[["x", "y", "z"]].to_numpy()
        _check(source, t, hand)
        return TrajectoryTable(t, "hand", hand, None, source)
    joints = {}
    for j in SKELETON_JOINTS:
        cols = [f"{j}_{a}" for a in "xyz"]
        if set(cols) <= set(df.columns):
            joints[j] = df[cols].to_numpy()
    if "torso" not in joints or "right_hand" not in joints:
        raise DataError(
            f"{source}: expected columns t, x, y, z (the hand in the torso frame) or a skeleton with "
            f"torso_x … right_hand_z (and left_shoulder, right_shoulder, neck for the body size); "
            f"columns: {', '.join(df.columns)}"
        )
    for j in ("torso", "right_hand"):
        _check(source, t, joints[j], what=j)
    return TrajectoryTable(t, "skeleton", None, joints, source)


def _check(source: str, t: np.ndarray, xyz: np.ndarray, what: str = "x, y, z") -> None:
    if len(t) == 0:
        raise DataError(f"{source}: no frames")
    bad = np.flatnonzero(~np.isfinite(t) | np.r_[False, np.diff(t) <= 0])
    if bad.size:
        raise DataError(f"{source}: row {bad[0] + 2}: t must be finite and strictly increasing")
    rows = np.flatnonzero(~np.all(np.isfinite(xyz), axis=1) | np.any(np.abs(xyz) > 100, axis=1))
    if rows.size:
        raise DataError(f"{source}: row {rows[0] + 2}: {what} must be finite and within ±100 m")


def _from_array(arr: np.ndarray, source: str) -> TrajectoryTable:
    if arr.ndim == 2 and arr.shape[1] == 4:
        t, hand = arr[:, 0].astype(float), arr[:, 1:].astype(float)
    elif arr.ndim == 2 and arr.shape[1] == 3:
        hand = arr.astype(float)
        t = np.arange(len(hand)) / NPY_FRAME_RATE
    elif arr.ndim == 3 and arr.shape[1:] == (15, 3):
        t = np.arange(len(arr)) / NPY_FRAME_RATE
        joints = {j: arr[:, OPENNI_JOINTS.index(j), :].astype(float) for j in SKELETON_JOINTS}
        for j in ("torso", "right_hand"):
            _check(source, t, joints[j], what=j)
        return TrajectoryTable(t, "skeleton", None, joints, source)
    else:
        raise DataError(
            f"{source}: an array of shape {arr.shape}; expected (T, 4) t x y z, (T, 3) x y z, "
            "or (T, 15, 3) an OpenNI skeleton"
        )
    _check(source, t, hand)
    return TrajectoryTable(t, "hand", hand, None, source)
