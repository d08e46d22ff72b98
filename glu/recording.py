"""Rerun recordings (``.rrd``) of what unfolds over time: trajectories, series, bars, text, skeletons.

One function per concept, explicit ``frame`` and ``time`` timelines (or an ``episode`` timeline), whole
series sent with ``send_columns``. Each file is written headless through its own
:class:`rerun.RecordingStream` with an explicit recording id and no log time (:func:`new_recording`), and
closed with ``disconnect()`` so the footer is written: the same data give the same recording, equal under
``rerun rrd compare`` (the bytes are not: Rerun stamps each chunk and row with an id of its own). Open one
with ``rerun FILE.rrd``.

The studies compose these into their recordings, each with its blueprint (the viewer's layout):
:mod:`glu.studies.anticipation.recordings` (effect anticipation), :mod:`glu.studies.correspondence.recordings`
(one gesture, two viewpoints), :mod:`glu.studies.learning.recordings` (learning gestures online).
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

ACTION_RGB = {
    "grasp": (76, 114, 176),
    "tap": (221, 132, 82),
    "touch": (85, 168, 104),
    "push": (129, 114, 179),
}
VALUE_RGB = {"slow": (141, 160, 203), "medium": (252, 141, 98), "fast": (102, 194, 165)}
"""Colours of the values in the bar charts (the figures' colours)."""


def rerun():
    """The ``rerun`` module, imported on first use (it is an extra: ``glu[notebooks]``)."""
    import rerun as rr

    return rr


def new_recording(path: str | os.PathLike, recording_id: str, blueprint=None, application_id: str = "glu"):
    """Open a RecordingStream that writes to ``path`` (log time off, so same data → same content)."""
    rr = rerun()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # no time-based flushing: the chunks of a file depend on its data only, not on how fast it was logged
    rec = rr.RecordingStream(
        application_id,
        recording_id=recording_id,
        send_properties=False,
        batcher_config=rr.ChunkBatcherConfig.NEVER(),
    )
    rec.set_log_time_enabled(False)
    rec.save(str(path), default_blueprint=blueprint)
    return rec


def log_trajectory(rec, xyz: np.ndarray, frames: np.ndarray, seconds: np.ndarray) -> None:
    """The hand position and its growing path, one row per frame (xyz: shape (n_frames, 3))."""
    rr = rerun()
    xyz = np.asarray(xyz, dtype=np.float32)
    for k, (f, t) in enumerate(zip(frames, seconds, strict=True)):
        rec.set_time("frame", sequence=int(f))
        rec.set_time("time", duration=float(t))
        rec.log("hand/position", rr.Points3D(xyz[k : k + 1], radii=0.02, colors=(255, 200, 0)))
        rec.log("hand/path", rr.LineStrips3D([xyz[: k + 1]], radii=0.004, colors=(200, 200, 200)))


def log_series(
    rec, entity: str, values: np.ndarray, names: Sequence[str], frames: np.ndarray, seconds: np.ndarray
) -> None:
    """One time series per column of ``values`` (shape (n_frames, n_series)) under ``entity/<name>``."""
    rr = rerun()
    values = np.asarray(values, dtype=float)
    for j, name in enumerate(names):
        color = ACTION_RGB.get(name, (120, 120, 120))
        rec.log(f"{entity}/{name}", rr.SeriesLines(names=name, colors=color), static=True)
        finite = np.isfinite(values[:, j])
        rec.send_columns(
            f"{entity}/{name}",
            indexes=[
                rr.TimeColumn("frame", sequence=np.asarray(frames)[finite].astype(np.int64)),
                rr.TimeColumn("time", duration=np.asarray(seconds)[finite].astype(float)),
            ],
            columns=rr.Scalars.columns(scalars=values[finite, j]),
        )


def log_updates(
    rec, entity: str, probs: np.ndarray, values: Sequence[str], frames: np.ndarray, seconds: np.ndarray
) -> None:
    """Probabilities updated every few frames: ``probs`` shape (n_updates, n_values), one row per update
    frame, one named series per value under ``entity/<value>`` (a line through the updates, a point at
    each), so that a time-series view names each value in its legend and labels its frame axis.

    (Rerun's bar charts name a bar by its entity path only, and label no category.)
    """
    rr = rerun()
    probs = np.asarray(probs, dtype=float)
    indexes = [
        rr.TimeColumn("frame", sequence=np.asarray(frames, dtype=np.int64)),
        rr.TimeColumn("time", duration=np.asarray(seconds, dtype=float)),
    ]
    for j, value in enumerate(values):
        color = VALUE_RGB.get(value) or ACTION_RGB.get(value) or (120, 120, 120)
        rec.log(  # one row, one chunk: two calls would be batched into chunks that differ from run to run
            f"{entity}/{value}",
            rr.SeriesLines(names=value, colors=color, widths=2.0),
            rr.SeriesPoints(names=value, colors=color, marker_sizes=3.0),
            static=True,
        )
        rec.send_columns(
            f"{entity}/{value}", indexes=indexes, columns=rr.Scalars.columns(scalars=probs[:, j])
        )


def markdown_text(text: str) -> str:
    """Plain text made safe for a Markdown panel: characters Markdown would read as markup are escaped
    (Rerun's text panel renders Markdown, not HTML)."""
    return re.sub(r"([\\`*_{}\[\]<>()#+!|~])", r"\\\1", text)


def log_scene(rec, markdown: str, note: str = "") -> None:
    """The static text panel describing the scene; ``note`` (plain text: the data and the run's
    parameters) ends it, after a rule."""
    rr = rerun()
    text = markdown + (f"\n\n---\n\n{markdown_text(note)}" if note else "")
    rec.log("scene", rr.TextDocument(text, media_type="text/markdown"), static=True)


def log_texts(rec, entity: str, texts: Sequence[str], frames: np.ndarray, seconds: np.ndarray) -> None:
    """Text lines at given frames (e.g. the current best verbal description).

    ``texts``, ``frames`` (frame numbers) and ``seconds`` (their times in s from the start): one entry per
    line, shape (n_texts,) each.
    """
    rr = rerun()
    for text, f, t in zip(texts, frames, seconds, strict=True):
        rec.set_time("frame", sequence=int(f))
        rec.set_time("time", duration=float(t))
        rec.log(entity, rr.TextLog(text, level=rr.TextLogLevel.INFO))


SKELETON_BONES: tuple[tuple[str, ...], ...] = (
    ("head", "neck", "torso"),
    ("left_hand", "left_elbow", "left_shoulder", "neck", "right_shoulder", "right_elbow", "right_hand"),
    ("left_foot", "left_knee", "left_hip", "torso", "right_hip", "right_knee", "right_foot"),
)
"""Chains of OpenNI joints drawn as the skeleton."""


def log_skeleton(rec, entity: str, skeleton: np.ndarray, joints: Sequence[str], seconds: np.ndarray) -> None:
    """A skeleton over time, shape (n_frames, n_joints, 3): its joints as points and bones as line strips."""
    rr = rerun()
    index = {j: k for k, j in enumerate(joints)}
    chains = [[index[j] for j in chain] for chain in SKELETON_BONES]
    for k, t in enumerate(seconds):
        rec.set_time("frame", sequence=k + 1)
        rec.set_time("time", duration=float(t))
        pts = np.asarray(skeleton[k], dtype=np.float32)
        rec.log(f"{entity}/joints", rr.Points3D(pts, radii=0.015, colors=(90, 90, 90)))
        rec.log(
            f"{entity}/bones", rr.LineStrips3D([pts[c] for c in chains], radii=0.006, colors=(120, 120, 120))
        )


def log_path(rec, entity: str, xyz: np.ndarray, seconds: np.ndarray, color: tuple[int, int, int]) -> None:
    """A 3-D path growing frame by frame (``xyz`` shape (n_frames, 3)), its current point marked."""
    rr = rerun()
    xyz = np.asarray(xyz, dtype=np.float32)
    for k, t in enumerate(seconds):
        rec.set_time("frame", sequence=k + 1)
        rec.set_time("time", duration=float(t))
        rec.log(f"{entity}/position", rr.Points3D(xyz[k : k + 1], radii=0.03, colors=color))
        rec.log(f"{entity}/path", rr.LineStrips3D([xyz[: k + 1]], radii=0.008, colors=color))


def log_series_on(rec, entity: str, values: np.ndarray, names: Sequence[str], steps: np.ndarray) -> None:
    """One series per column of ``values`` (shape (n, k)) under ``entity/<name>`` on the ``episode``
    timeline."""
    rr = rerun()
    for j, name in enumerate(names):
        rec.log(
            f"{entity}/{name}",
            rr.SeriesLines(names=name, colors=ACTION_RGB.get(name, (90, 90, 90))),
            static=True,
        )
        rec.send_columns(
            f"{entity}/{name}",
            indexes=[rr.TimeColumn("episode", sequence=np.asarray(steps, dtype=np.int64))],
            columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=float)[:, j]),
        )
