"""Reading a gesture recording: the one place where a file becomes features, repaired and segmented.

The data modules read a file into arrays (:mod:`glu.data.hand_logs`: YARP hand logs;
:mod:`glu.data.trajectory_files`: CSV, TSV and NPY tables); the features (:mod:`glu.gestures.features`), the
repair (:mod:`glu.gestures.trajectories`) and the segmentation (:mod:`glu.gestures.segmentation`) are pure
functions over arrays. The functions here compose them, each recording read once:

* :func:`read_recording` — a recording's model features as recorded, a
  :class:`~glu.gestures.trajectories.Trajectory` (YARP logs / 1000, tables by body size or skeleton);
* :func:`load_features` — the same, repaired (:func:`~glu.gestures.trajectories.repair`);
* :func:`segment_recording` — the same, each repaired piece segmented into repetitions
  (:func:`~glu.gestures.segmentation.segment_repetitions`);
* :func:`read_hand_log` and :func:`parse_hand_log` — a YARP hand log as logged (×1000 the model units).

Example
-------
>>> import numpy as np, tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> t = np.arange(40) / 30.0
>>> xyz = np.stack([np.sin(t), np.cos(t), t], axis=1) * 1000.0          # as logged: 1000 × model units
>>> from glu.data.hand_logs import write_hand_log
>>> path = write_hand_log(folder / "wave", t, xyz)
>>> traj = read_recording(path)
>>> traj.xyz.shape, bool(np.allclose(traj.xyz, xyz / 1000.0))
((40, 3), True)
"""

from __future__ import annotations

import os
from pathlib import Path

from glu.data import hand_logs
from glu.data.trajectory_files import is_trajectory_file, read_trajectory_table
from glu.gestures.features import log_features, table_features
from glu.gestures.segmentation import (
    DEFAULT_PARAMS,
    RecordingSegmentation,
    SegmentationParams,
    segment_repetitions,
)
from glu.gestures.trajectories import DEFAULT_POLICY, Repaired, RepairPolicy, Trajectory, repair


def read_hand_log(path: str | os.PathLike) -> Trajectory:
    """Read a YARP hand log (a ``data.log`` file or a recording folder holding one), as logged (no repair).

    The format and its errors are :mod:`glu.data.hand_logs`'; frames are numbered 1, 2, … in file order.
    """
    log = hand_logs.read_hand_log(path)
    return Trajectory.recorded(log.xyz, log.t, log.source)


def parse_hand_log(data: bytes | str, source: str = "<string>") -> Trajectory:
    """Parse the text of a YARP hand log (see :func:`read_hand_log`); ``source`` names it in errors."""
    log = hand_logs.parse_hand_log(data, source)
    return Trajectory.recorded(log.xyz, log.t, log.source)


def read_recording(path: str | os.PathLike, body: tuple[float, float] | None = None) -> Trajectory:
    """A recording — a YARP hand log, or a CSV/TSV/NPY table — as model features, unrepaired.

    YARP logs are converted by :func:`~glu.gestures.features.log_features`, tables by
    :func:`~glu.gestures.features.table_features` (``body``: the body size of a hand table, metres).
    """
    if is_trajectory_file(path):
        table = read_trajectory_table(path)  # the file's arrays
        return table_features(table, body)
    log = read_hand_log(path)
    return log.with_xyz(log_features(log.xyz))


def load_features(
    path: str | os.PathLike,
    policy: RepairPolicy | None = DEFAULT_POLICY,
    body: tuple[float, float] | None = None,
) -> Repaired:
    """:func:`read_recording`, repaired by ``policy`` (``None``: no repair). Returns the pieces and events of
    :func:`glu.gestures.trajectories.repair` (one piece, no events if ``None``)."""
    traj = read_recording(path, body)
    if policy is None:
        return Repaired([traj], ())
    return repair(traj, policy)


def segment_recording(
    path: str | os.PathLike,
    label: str | None = None,
    policy: RepairPolicy = DEFAULT_POLICY,
    params: SegmentationParams = DEFAULT_PARAMS,
) -> RecordingSegmentation:
    """Read a recording (a YARP hand log, file or recording folder, or a table), repair it and segment each
    piece into repetitions.

    ``label`` is the action performed, if known (:func:`glu.gestures.corpus.segment_recording_of` fills it
    in for the recordings of a data folder).
    """
    p = Path(path)
    name = p.name if p.is_dir() else p.parent.name if p.name == hand_logs.FILE_NAME else p.stem
    repaired = load_features(path, policy)
    pieces = [
        segment_repetitions(tr, label, params, recording=name) for tr in repaired.pieces if len(tr) >= 2
    ]
    return RecordingSegmentation(name, pieces, repaired.events)
