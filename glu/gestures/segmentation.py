"""Gesture segments: the original frame ranges, and automatic segmentation of a recording into repetitions.

The originals cut their test segments by hand (docs/method.md
§4.3, :data:`glu.gestures.corpus.ORIGINAL_SEGMENTS`). For training, the recordings ``grasp1_hand``,
``tap1_hand``, ``touch1_hand`` and ``push1_hand`` hold several repetitions of one gesture
each; :func:`segment_repetitions` finds them automatically:

1. the trajectory (feature units) is cleaned by a running median and smoothed by a moving average;
2. the **rest pose** is the median position of the frames whose z is in the top ``1 - rest_quantile``
   (the hand nearest the person's back: every gesture reaches forward, towards the table, z < 0);
3. the **activity** is the distance to the rest pose, divided by its 95th percentile (so 1 is a full
   reach, whatever the person's size or the gesture);
4. a repetition is a run of frames with activity above ``enter``, extended outwards while the activity
   keeps falling and stays above ``exit`` (two repetitions that meet are cut at the activity minimum
   between them), then trimmed of still frames at both ends (the hand at rest somewhere other than the
   rest pose). It is kept if it lasts at least ``min_frames``, its activity peaks above ``min_peak``,
   it holds no tracking jump longer than ``max_jump``, and it does not reach either end of the
   trajectory (a repetition cut by the start or the end of the recording, or by a tracking gap that
   split the trajectory, is *partial*).

The parameters are a :class:`SegmentationParams`; the defaults were chosen by looking at the six real
recordings (the figure of :func:`glu.studies.replication.gesture_figures.plot_segmentation`) and are checked
on synthetic recordings with known repetitions. Segments are 1-based inclusive frame ranges of the source
log, as in the papers.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import NamedTuple

import numpy as np

from glu.errors import DataError
from glu.gestures.trajectories import (
    TrackingEvent,
    Trajectory,
    summarize_events,
)


@dataclass(frozen=True)
class Segment:
    """A gesture segment: frames ``start`` … ``end`` (1-based, inclusive) of a recording.

    Attributes
    ----------
    start, end : first and last frame, in the numbering of the source log
    label : the action, if known
    recording : the recording's name (or the log's path)
    peak : the segment's peak activity (automatic segmentation), or NaN
    """

    start: int
    end: int
    label: str | None = None
    recording: str = ""
    peak: float = float("nan")

    @property
    def n_frames(self) -> int:
        """``end - start + 1``."""
        return self.end - self.start + 1

    def describe(self) -> str:
        """``start:end (n frames)``, with the label if any."""
        lab = f" {self.label}" if self.label else ""
        return f"{self.start}:{self.end} ({self.n_frames} frames){lab}"

    def as_dict(self) -> dict:
        """``{start, end, frames, peak, label}`` in plain Python types (peak None when NaN)."""
        peak = float(self.peak)
        return {
            "start": int(self.start),
            "end": int(self.end),
            "frames": int(self.n_frames),
            "peak": peak if np.isfinite(peak) else None,
            "label": self.label,
        }


@dataclass(frozen=True)
class SegmentationParams:
    """Parameters of :func:`segment_repetitions` (frames at about 30 per second; feature units).

    Attributes
    ----------
    median_window : frames of the running median that removes spikes
    smooth_window : frames of the moving average
    rest_quantile : the rest pose is the median of the frames with z above this quantile of z
    enter : activity above which a repetition is under way
    exit : a segment is extended outwards while the activity falls and stays above this
    still_speed : feature units per frame; slower frames at the ends of a segment are trimmed
    min_frames : shortest repetition kept
    min_peak : a segment's activity must peak at least this high (1 is a full reach)
    max_jump : a segment with a step longer than this between frames (tracking lost the hand) is left out
    keep_partial : keep repetitions cut by the start or end of the trajectory
    """

    median_window: int = 7
    smooth_window: int = 5
    rest_quantile: float = 0.9
    enter: float = 0.5
    exit: float = 0.12
    still_speed: float = 0.012
    min_frames: int = 45
    min_peak: float = 0.65
    max_jump: float = 1.0
    keep_partial: bool = False


DEFAULT_PARAMS = SegmentationParams()
"""The segmentation parameters glu uses (chosen on the six real recordings, checked on synthetic ones)."""


class Segmentation(NamedTuple):
    """The result of :func:`segment_repetitions` on one trajectory.

    Attributes
    ----------
    segments : the repetitions kept, in time order
    rejected : (segment, reason) for the candidates left out
    activity : array, shape (n_frames,), the activity signal
    rest : array, shape (3,), the rest pose
    trajectory : the trajectory segmented
    """

    segments: list[Segment]
    rejected: list[tuple[Segment, str]]
    activity: np.ndarray
    rest: np.ndarray
    trajectory: Trajectory


def smooth(xyz: np.ndarray, params: SegmentationParams = DEFAULT_PARAMS) -> np.ndarray:
    """Running median then moving average, per axis; ``xyz`` has shape (n_frames, 3), so has the result."""
    from scipy.ndimage import median_filter, uniform_filter1d

    xyz = np.asarray(xyz, dtype=float)
    out = median_filter(xyz, size=(params.median_window, 1), mode="nearest")
    return uniform_filter1d(out, params.smooth_window, axis=0, mode="nearest")


def activity_signal(
    xyz: np.ndarray, params: SegmentationParams = DEFAULT_PARAMS
) -> tuple[np.ndarray, np.ndarray]:
    """The activity (distance to the rest pose / its 95th percentile) and the rest pose.

    Parameters
    ----------
    xyz : array, shape (n_frames, 3), feature units

    Returns
    -------
    activity : array, shape (n_frames,)
    rest : array, shape (3,)
    """
    s = smooth(xyz, params)
    if len(s) == 0:
        raise DataError("cannot segment an empty trajectory")
    zq = np.quantile(s[:, 2], params.rest_quantile)
    rest = np.median(s[s[:, 2] >= zq], axis=0)
    d = np.linalg.norm(s - rest, axis=1)
    scale = np.quantile(d, 0.95)
    return (d / scale if scale > 0 else np.zeros_like(d)), rest


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open [a, b) index runs where ``mask`` is True."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(), strict=True))


def segment_repetitions(
    traj: Trajectory,
    label: str | None = None,
    params: SegmentationParams = DEFAULT_PARAMS,
    recording: str = "",
) -> Segmentation:
    """Find the repetitions of a gesture in a trajectory in feature units (one piece, see :func:`repair`).

    Returns the segments (1-based inclusive frames of the source log), the candidates rejected and why,
    and the activity signal.
    """
    n = len(traj)
    if n < 2:
        raise DataError(f"{traj.source}: {n} frame(s) cannot be segmented")
    activity, rest = activity_signal(traj.xyz, params)
    speed = np.r_[0.0, np.linalg.norm(np.diff(smooth(traj.xyz, params), axis=0), axis=1)]
    runs = _runs(activity > params.enter)
    # extend each run outwards while the activity falls and stays above `exit`; neighbours that meet
    # share the boundary at the activity minimum between them
    ext = []
    for a, b in runs:
        while a > 0 and params.exit < activity[a - 1] <= activity[a]:
            a -= 1
        while b < n and params.exit < activity[b] <= activity[b - 1]:
            b += 1
        ext.append([a, b])
    for k in range(len(ext) - 1):
        if ext[k][1] > ext[k + 1][0]:
            lo, hi = runs[k][1], runs[k + 1][0]
            cut = lo + int(np.argmin(activity[lo:hi])) if hi > lo else lo
            ext[k][1], ext[k + 1][0] = cut, cut
    steps = np.r_[0.0, np.linalg.norm(np.diff(traj.xyz, axis=0), axis=1)]
    name = recording or traj.source
    segments, rejected = [], []
    for a, b in ext:
        partial = a == 0 or b == n
        while b - a > 1 and speed[a + 1] < params.still_speed:  # trim still frames at both ends
            a += 1
        while b - a > 1 and speed[b - 1] < params.still_speed:
            b -= 1
        s = Segment(int(traj.frame[a]), int(traj.frame[b - 1]), label, name, float(activity[a:b].max()))
        jump = float(steps[a + 1 : b].max()) if b - a > 1 else 0.0
        if partial and not params.keep_partial:
            rejected.append((s, "partial: cut by the start or end of the trajectory"))
        elif b - a < params.min_frames:
            rejected.append((s, f"shorter than {params.min_frames} frames"))
        elif s.peak < params.min_peak:
            rejected.append((s, f"peak activity {s.peak:.2f} below {params.min_peak}"))
        elif jump > params.max_jump:
            rejected.append((s, f"tracking jump of {jump:.2f} (more than {params.max_jump})"))
        else:
            segments.append(s)
    rejected.sort(key=lambda r: r[0].start)
    return Segmentation(segments, rejected, activity, rest, traj)


def extract(traj: Trajectory, segment: Segment) -> np.ndarray:
    """The coordinates of a segment's frames, shape (n_frames, 3) (repaired frames within it included)."""
    sel = (traj.frame >= segment.start) & (traj.frame <= segment.end)
    if not sel.any():
        raise DataError(f"{traj.source}: segment {segment.describe()} has no frame in this trajectory")
    return traj.xyz[sel]


@dataclass(frozen=True)
class RecordingSegmentation:
    """The automatic segmentation of a whole recording (every repaired piece).

    Attributes
    ----------
    recording : its name
    pieces : one :class:`Segmentation` per piece left by :func:`repair`
    events : the tracking events found
    """

    recording: str
    pieces: list[Segmentation]
    events: tuple[TrackingEvent, ...] = field(default=())

    @property
    def segments(self) -> list[Segment]:
        """All segments kept, in time order."""
        return [s for p in self.pieces for s in p.segments]

    @property
    def rejected(self) -> list[tuple[Segment, str]]:
        """All candidates rejected, with the reason."""
        return [r for p in self.pieces for r in p.rejected]

    def as_dict(self) -> dict:
        """``{recording, tracking, events, segments, left_out}`` in plain Python types (for JSON)."""
        return {
            "recording": self.recording,
            "tracking": summarize_events(self.events),
            "events": [
                {**asdict(e), "frame": int(e.frame), "time": float(e.time), "size": float(e.size)}
                for e in self.events
            ],
            "segments": [s.as_dict() for s in self.segments],
            "left_out": [{**s.as_dict(), "reason": why} for s, why in self.rejected],
        }
