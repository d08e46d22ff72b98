"""Hand trajectories: a 3-D path with its timing, tracking gaps and outliers, and their repair.

A :class:`Trajectory` holds a recording's arrays (:func:`glu.gestures.recordings.read_recording` makes one
from a YARP hand log or a table; this module reads no file). Frames are numbered 1, 2, … in file order, the
numbering of the papers' segment ranges.

Real tracking drops out and jumps. :func:`repair` detects, reports and (by a :class:`RepairPolicy`) repairs:

* **gaps** — a time step above ``gap_factor`` × the frame period (the median time step). Gaps up to
  ``max_interpolate`` seconds are filled with frames at the frame period, linearly interpolated; longer
  ones split the trajectory into pieces (or are kept, if ``long_gaps="keep"``).
* **spikes** — isolated outliers: frames farther than ``spike_threshold`` from the running median of
  ``spike_window`` frames (so at most ``spike_window // 2`` consecutive frames). They are replaced by
  linear interpolation from their neighbours in time (or dropped, or kept).
* **jumps** — a step between consecutive frames longer than ``jump_threshold`` (after spike repair):
  a sudden displacement of the tracked hand that persists, which cannot be told from real motion
  frame by frame. Jumps are reported, never changed.

The thresholds are in the units of the trajectory; the defaults are for feature units (the logs divided
by 1000; one unit is about a shoulder width horizontally, a neck–torso distance vertically). Repaired
frames keep ``observed == False`` and the frame number of the last observed frame before them, so
segments are always reported in the numbering of the original log.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np

from glu.errors import DataError


@dataclass(frozen=True)
class TrackingEvent:
    """A tracking problem found in a trajectory, and what the repair policy did about it.

    Attributes
    ----------
    kind : ``"gap"``, ``"spike"``, ``"jump"``, ``"missing"`` (a frame without coordinates) or
        ``"short-piece"`` (a piece left too short after splitting, dropped)
    frame : 1-based frame of the source log: the first frame after a gap or jump, the outlier frame
    time : seconds since the first frame of the source
    size : gap: its duration in seconds; spike: distance to the running median; jump: step length;
        short-piece: its number of frames
    action : ``"interpolated"``, ``"split"``, ``"replaced"``, ``"dropped"`` or ``"kept"``
    """

    kind: str
    frame: int
    time: float
    size: float
    action: str

    def describe(self) -> str:
        """One line, e.g. ``gap of 1.54 s before frame 339 (t=10.31 s): split``."""
        if self.kind == "gap":
            what = f"gap of {self.size:.2f} s before frame {self.frame}"
        elif self.kind == "spike":
            what = f"spike at frame {self.frame} ({self.size:.2f} from the running median)"
        elif self.kind == "jump":
            what = f"jump of {self.size:.2f} before frame {self.frame}"
        elif self.kind == "short-piece":
            what = f"piece of {int(self.size)} frames from frame {self.frame}"
        else:
            what = f"{self.kind} at frame {self.frame}"
        return f"{what} (t={self.time:.2f} s): {self.action}"


def checked_arrays(xyz: np.ndarray, t: np.ndarray, source: str) -> tuple[np.ndarray, np.ndarray]:
    """``xyz`` and ``t`` as float arrays; DataError naming ``source`` unless ``xyz`` has shape (n, 3) for
    ``n = len(t)`` and the timestamps are finite and strictly increasing."""
    xyz, t = np.asarray(xyz, dtype=float), np.asarray(t, dtype=float)
    n = len(t)
    if xyz.shape != (n, 3):
        raise DataError(f"{source}: xyz must have shape (n_frames, 3) = ({n}, 3), got {xyz.shape}")
    if n and (not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0)):
        raise DataError(f"{source}: timestamps must be finite and strictly increasing")
    return xyz, t


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A 3-D hand trajectory with its timing.

    Attributes
    ----------
    xyz : array, shape (n_frames, 3) — x right (the person's view), y up, z towards the person's back
    t : array, shape (n_frames,) — timestamps in seconds, strictly increasing
    frame : int array, shape (n_frames,) — 1-based frame number in the source log (repaired frames
        carry the number of the last observed frame before them)
    observed : bool array, shape (n_frames,) — False for frames made by interpolation
    source : where the trajectory comes from (a file path, or a description)
    events : the tracking problems found so far (see :func:`repair`)
    """

    xyz: np.ndarray
    t: np.ndarray
    frame: np.ndarray
    observed: np.ndarray
    source: str = "<memory>"
    events: tuple[TrackingEvent, ...] = field(default=())

    def __post_init__(self) -> None:
        xyz, t = checked_arrays(self.xyz, self.t, self.source)
        n = len(t)
        frame = np.asarray(self.frame, dtype=np.int64)
        observed = np.asarray(self.observed, dtype=bool)
        if frame.shape != (n,) or observed.shape != (n,):
            raise DataError(f"{self.source}: frame and observed must have shape ({n},)")
        for name, value in (("xyz", xyz), ("t", t), ("frame", frame), ("observed", observed)):
            value.flags.writeable = False
            object.__setattr__(self, name, value)

    @classmethod
    def recorded(cls, xyz: np.ndarray, t: np.ndarray, source: str = "<memory>") -> Trajectory:
        """Frames 1 … n of a source log as it was read: every one observed, no event yet.

        ``xyz``, shape (n, 3), in the source's units (a hand log's logged units, or feature units); ``t``,
        shape (n,), seconds, strictly increasing.
        """
        return cls(xyz, t, np.arange(1, len(t) + 1), np.ones(len(t), dtype=bool), source)

    def __len__(self) -> int:
        return len(self.t)

    def with_xyz(self, xyz: np.ndarray) -> Trajectory:
        """The same frames and timing with other coordinates, shape (n_frames, 3)."""
        return replace(self, xyz=np.asarray(xyz, dtype=float))

    def take(self, index: np.ndarray | slice) -> Trajectory:
        """The frames selected by a positional index (a slice, an int array of shape (k,), or a bool mask of
        shape (n_frames,))."""
        return replace(
            self, xyz=self.xyz[index], t=self.t[index], frame=self.frame[index], observed=self.observed[index]
        )

    def frames(self, first: int, last: int) -> Trajectory:
        """The frames numbered ``first`` … ``last`` of the source log (1-based, inclusive)."""
        if len(self.frame) == 0:
            raise DataError(f"{self.source}: the trajectory has no frames")
        lo, hi = int(self.frame.min()), int(self.frame.max())
        if not (lo <= first <= last <= hi):
            raise DataError(
                f"{self.source}: frames {first}:{last} are out of range; allowed: {lo} ≤ first ≤ last ≤ {hi}"
            )
        return self.take((self.frame >= first) & (self.frame <= last))


@dataclass(frozen=True)
class RepairPolicy:
    """What :func:`repair` does with gaps, spikes and jumps (thresholds in the trajectory's units).

    Attributes
    ----------
    gap_factor : a time step above ``gap_factor`` × the frame period is a gap
    max_interpolate : seconds; gaps up to this long are filled by linear interpolation (0: none)
    long_gaps : ``"split"`` (cut the trajectory into pieces) or ``"keep"`` (leave the frames as they are)
    spike_window : frames in the running median (odd, ≥ 3); spikes up to ``spike_window // 2`` frames long
    spike_threshold : a frame farther than this from the running median is a spike (``inf``: no check)
    spikes : ``"interpolate"`` (replace from the neighbours), ``"drop"`` or ``"keep"``
    jump_threshold : a step longer than this between consecutive frames is reported as a jump
    min_piece : pieces shorter than this (frames) after splitting are dropped
    """

    gap_factor: float = 2.5
    max_interpolate: float = 0.5
    long_gaps: str = "split"
    spike_window: int = 7
    spike_threshold: float = 0.3
    spikes: str = "interpolate"
    jump_threshold: float = 0.5
    min_piece: int = 10

    def __post_init__(self) -> None:
        if self.long_gaps not in ("split", "keep"):
            raise DataError(f"long_gaps={self.long_gaps!r}; allowed: 'split', 'keep'")
        if self.spikes not in ("interpolate", "drop", "keep"):
            raise DataError(f"spikes={self.spikes!r}; allowed: 'interpolate', 'drop', 'keep'")
        if self.spike_window < 3 or self.spike_window % 2 == 0:
            raise DataError(f"spike_window={self.spike_window}; allowed: an odd number ≥ 3")
        if not self.gap_factor > 1 or not self.max_interpolate >= 0 or self.min_piece < 1:
            raise DataError("gap_factor must be > 1, max_interpolate ≥ 0 and min_piece ≥ 1")


DEFAULT_POLICY = RepairPolicy()
"""Interpolate gaps up to 0.5 s, split at longer ones, replace spikes, report jumps."""

DETECT_ONLY = RepairPolicy(max_interpolate=0.0, long_gaps="keep", spikes="keep", min_piece=1)
"""Report everything, change nothing."""


class Repaired(NamedTuple):
    """The result of :func:`repair`: the usable pieces, in time order, and every event found."""

    pieces: list[Trajectory]
    events: tuple[TrackingEvent, ...]


def spike_deviation(xyz: np.ndarray, window: int = 7) -> np.ndarray:
    """Distance of each frame to the running median of ``window`` frames; ``> threshold`` marks a spike.

    Parameters
    ----------
    xyz : array, shape (n_frames, 3)

    Returns
    -------
    array, shape (n_frames,) (zeros when there are fewer frames than ``window``)
    """
    from scipy.ndimage import median_filter

    xyz = np.asarray(xyz, dtype=float)
    if len(xyz) < window:
        return np.zeros(len(xyz))
    # the per-axis running median, edges padded by repeating the end frames
    return np.linalg.norm(xyz - median_filter(xyz, size=(window, 1), mode="nearest"), axis=1)


def repair(traj: Trajectory, policy: RepairPolicy = DEFAULT_POLICY) -> Repaired:
    """Detect gaps, spikes and jumps in ``traj``, report them, and repair them as ``policy`` says.

    Frames with non-finite coordinates are removed first (reported as ``missing``), so a dropout
    becomes a gap. Returns the pieces (one unless gaps split it) and the events, in time order.
    """
    # Works on plain arrays and builds a Trajectory only for each returned piece (a corpus repairs
    # every one of a million synthetic gestures).
    events: list[TrackingEvent] = []
    t0 = float(traj.t[0]) if len(traj) else 0.0
    spans = _repair_spans(traj.xyz, traj.t, traj.frame, traj.observed, policy, traj.source, events, t0)
    kept = []
    for arrays in spans:
        if len(arrays[1]) >= policy.min_piece:
            kept.append(arrays)
        else:
            events.append(
                TrackingEvent(
                    "short-piece", int(arrays[2][0]), float(arrays[1][0] - t0), len(arrays[1]), "dropped"
                )
            )
    events.sort(key=lambda e: (e.frame, e.time))  # stable: a short piece after the events of its frame
    all_events = tuple(events)
    out = []
    for a_xyz, a_t, a_frame, a_obs in kept:
        lo, hi = int(a_frame[0]), int(a_frame[-1])
        own = tuple(e for e in all_events if lo <= e.frame <= hi)
        out.append(Trajectory(a_xyz, a_t, a_frame, a_obs, traj.source, traj.events + own))
    if not out:
        raise DataError(f"{traj.source}: no piece of at least {policy.min_piece} frames is left after repair")
    return Repaired(out, traj.events + all_events)


def repaired_xyz(
    xyz: np.ndarray,
    t: np.ndarray,
    policy: RepairPolicy = DEFAULT_POLICY,
    deviation: np.ndarray | None = None,
    source: str = "<memory>",
) -> np.ndarray:
    """The coordinates :func:`repair` gives, its pieces one after the other, without building its events.

    Parameters
    ----------
    xyz : array, shape (n_frames, 3); t : array, shape (n_frames,), strictly increasing (seconds)
    policy : the repair
    deviation : optional, shape (n_frames,): :func:`spike_deviation` of ``xyz`` if already computed
        (e.g. by :func:`spike_deviations` for many trajectories)
    source : names the trajectory in errors

    Returns
    -------
    array, shape (n_repaired, 3): ``np.concatenate([p.xyz for p in repair(traj, policy).pieces])``
    """
    xyz, t = checked_arrays(xyz, t, source)
    n = len(t)
    frame, observed = np.arange(1, n + 1), np.ones(n, dtype=bool)
    spans = _repair_spans(xyz, t, frame, observed, policy, source, None, 0.0, deviation)
    kept = [a[0] for a in spans if len(a[1]) >= policy.min_piece]
    if not kept:
        raise DataError(f"{source}: no piece of at least {policy.min_piece} frames is left after repair")
    return kept[0] if len(kept) == 1 else np.concatenate(kept)


def _repair_spans(
    xyz: np.ndarray,
    t: np.ndarray,
    frame: np.ndarray,
    observed: np.ndarray,
    policy: RepairPolicy,
    source: str,
    events: list[TrackingEvent] | None,
    t0: float,
    deviation: np.ndarray | None = None,
) -> list[list[np.ndarray]]:
    """The repaired pieces as ``[xyz, t, frame, observed]`` arrays; the events go to ``events`` (if given)."""

    def ev(kind: str, i: int, size: float, action: str) -> None:
        if events is not None:
            events.append(TrackingEvent(kind, int(frame[i]), float(t[i] - t0), float(size), action))

    finite = np.isfinite(xyz).all(axis=1)
    if not finite.all():
        for i in np.flatnonzero(~finite):
            ev("missing", int(i), 0.0, "dropped")
        xyz, t, frame, observed = xyz[finite], t[finite], frame[finite], observed[finite]
        deviation = None
    if len(t) == 0:
        raise DataError(f"{source}: no frame has finite coordinates")
    dt_all = np.diff(t)
    median_dt = np.median(dt_all) if len(t) > 1 else None
    period = float(median_dt) if median_dt is not None else 1 / 30

    # 1. spikes, on the observed frames
    if math.isfinite(policy.spike_threshold):
        n_before = len(t)
        xyz, t, frame, observed = _repair_spikes(xyz, t, frame, observed, policy, deviation, ev)
        if len(t) != n_before:  # spikes dropped
            dt_all = np.diff(t)
            median_dt = np.median(dt_all) if len(dt_all) else None

    # 2. jumps (reported only)
    if events is not None:
        steps = np.sqrt((np.diff(xyz, axis=0) ** 2).sum(axis=1))
        for i in np.flatnonzero(steps > policy.jump_threshold):
            ev("jump", int(i) + 1, steps[i], "kept")

    # 3. gaps: interpolate the short ones, split at (or keep) the long ones
    gaps = np.flatnonzero(dt_all > policy.gap_factor * median_dt) if len(dt_all) else dt_all.astype(int)
    return _gap_spans((xyz, t, frame, observed), gaps, period, policy, ev)


def _repair_spikes(
    xyz: np.ndarray,
    t: np.ndarray,
    frame: np.ndarray,
    observed: np.ndarray,
    policy: RepairPolicy,
    deviation: np.ndarray | None,
    ev: Callable[[str, int, float, str], None],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Step 1 of :func:`_repair_spans`: the spikes reported, and interpolated, dropped or kept."""
    dev = spike_deviation(xyz, policy.spike_window) if deviation is None else deviation
    spikes = dev > policy.spike_threshold
    if not spikes.any():
        return xyz, t, frame, observed
    action = {"interpolate": "replaced", "drop": "dropped", "keep": "kept"}[policy.spikes]
    for i in np.flatnonzero(spikes):
        ev("spike", int(i), dev[i], action)
    if policy.spikes == "interpolate" and (~spikes).sum() >= 2:
        good = ~spikes
        xyz = xyz.copy()
        for k in range(3):
            xyz[spikes, k] = np.interp(t[spikes], t[good], xyz[good, k])
        observed = observed & good
    elif policy.spikes == "drop":
        keep = ~spikes
        xyz, t, frame, observed = xyz[keep], t[keep], frame[keep], observed[keep]
    return xyz, t, frame, observed


def _gap_spans(
    arrays: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    gaps: np.ndarray,
    period: float,
    policy: RepairPolicy,
    ev: Callable[[str, int, float, str], None],
) -> list[list[np.ndarray]]:
    """Step 3 of :func:`_repair_spans`: the pieces ``[xyz, t, frame, observed]`` after the gaps (the frames
    before each of ``gaps``) are interpolated, split at or kept."""
    xyz, t, frame, _ = arrays
    spans: list[tuple[list[np.ndarray], ...]] = []  # per piece: its parts of xyz, t, frame, observed
    parts: tuple[list[np.ndarray], ...] = ([], [], [], [])
    start = 0

    def add(lo: int, hi: int) -> None:
        for part, arr in zip(parts, arrays, strict=True):
            part.append(arr[lo:hi])

    for g in gaps:
        dt = float(t[g + 1] - t[g])
        if dt > policy.max_interpolate and policy.long_gaps == "keep":
            ev("gap", int(g) + 1, dt, "kept")
            continue
        add(start, g + 1)
        start = g + 1
        if dt > policy.max_interpolate:
            ev("gap", int(g) + 1, dt, "split")
            spans.append(parts)
            parts = ([], [], [], [])
            continue
        ev("gap", int(g) + 1, dt, "interpolated")
        k = max(int(round(dt / period)) - 1, 0)
        if k:
            w = np.arange(1, k + 1) / (k + 1)
            parts[0].append(xyz[g] + w[:, None] * (xyz[g + 1] - xyz[g]))
            parts[1].append(t[g] + w * dt)
            parts[2].append(np.full(k, frame[g]))
            parts[3].append(np.zeros(k, dtype=bool))
    add(start, len(t))
    spans.append(parts)
    return [[a[0] if len(a) == 1 else np.concatenate(a) for a in p] for p in spans]


def summarize_events(events: tuple[TrackingEvent, ...] | list[TrackingEvent]) -> str:
    """One line counting the events by kind and action, e.g.
    ``2 gaps (1 interpolated, 1 split), 5 spikes``."""
    if not events:
        return "no tracking problems found"
    parts = []
    for kind in ("missing", "gap", "spike", "jump", "short-piece"):
        sel = [e for e in events if e.kind == kind]
        if not sel:
            continue
        detail = ", ".join(f"{n} {a}" for a, n in Counter(e.action for e in sel).items())
        parts.append(f"{len(sel)} {kind}{'s' if len(sel) != 1 else ''} ({detail})")
    return ", ".join(parts)


# ------------------------------------------------------------------ many trajectories at once
# The repair of many trajectories at once (:func:`glu.gestures.trajectories.repair`), bit for bit.
#
# A simulated corpus repairs every one of a million synthetic gestures, most of which need nothing done:
# no spike, no gap. :func:`repaired_many` finds those for all trajectories together — the running
# medians of the spike check in one pass over all frames (:func:`spike_deviations`), every frame period
# by one sort — returns their coordinates untouched, and repairs the others one by one with
# :func:`repaired_xyz` (the same code as :func:`repair`).


def spike_deviations(xyzs: Sequence[np.ndarray], window: int = 7) -> list[np.ndarray]:
    """:func:`~glu.gestures.trajectories.spike_deviation` of many trajectories, their medians in one pass.

    Parameters
    ----------
    xyzs : arrays of shape (n_i, 3), finite
    window : frames in the running median (odd)

    Returns
    -------
    one array of shape (n_i,) per trajectory, equal to ``spike_deviation(xyzs[i], window)`` (a median of
    an odd number of values is one of them, whatever finds it; here a sorting network over the windows
    of all frames, edges repeated as the median filter's ``"nearest"`` mode)
    """
    lengths = np.array([len(x) for x in xyzs], dtype=np.int64)
    out = [np.zeros(n) for n in lengths]
    idx = np.flatnonzero(lengths >= window)
    if len(idx) == 0:
        return out
    xyz = np.concatenate([np.asarray(xyzs[i], dtype=float) for i in idx])
    n = lengths[idx]
    half = window // 2
    # every trajectory padded by `half` repeated edge frames on each side, one after the other
    padded_n = n + 2 * half
    start = np.repeat(np.cumsum(n) - n, padded_n)
    local = np.arange(padded_n.sum()) - np.repeat(np.cumsum(padded_n) - padded_n, padded_n) - half
    padded = xyz[start + np.clip(local, 0, np.repeat(n - 1, padded_n))]
    width = len(padded) - window + 1
    v = [padded[j : j + width] for j in range(window)]  # v[j][p]: frame p + j of the padded frames
    for r in range(window):  # odd-even transposition sort: `window` rounds sort every window
        for j in range(r % 2, window - 1, 2):
            v[j], v[j + 1] = np.minimum(v[j], v[j + 1]), np.maximum(v[j], v[j + 1])
    centre = np.arange(len(xyz)) + np.repeat(np.arange(len(n)) * 2 * half, n)  # each frame's own window
    dev = np.linalg.norm(xyz - v[half][centre], axis=1)
    for i, piece in zip(idx, np.split(dev, np.cumsum(n)[:-1]), strict=True):
        out[i] = piece
    return out


def repaired_many(
    xyzs: Sequence[np.ndarray],
    ts: Sequence[np.ndarray],
    policy: RepairPolicy = DEFAULT_POLICY,
    **changes: float | int | str,
) -> list[np.ndarray]:
    """:func:`~glu.gestures.trajectories.repaired_xyz` of many trajectories.

    Parameters
    ----------
    xyzs : arrays of shape (n_i, 3)
    ts : arrays of shape (n_i,), strictly increasing timestamps (seconds)
    policy : the repair; ``changes`` replace some of its fields (e.g. ``min_piece=1``)

    Returns
    -------
    one array of shape (m_i, 3) per trajectory: its repaired pieces one after the other
    """
    if changes:
        policy = RepairPolicy(**{**policy.__dict__, **changes})
    if len(xyzs) != len(ts):
        raise DataError(f"{len(xyzs)} coordinate arrays but {len(ts)} timestamp arrays")
    xyzs = [np.asarray(x, dtype=float) for x in xyzs]
    ts = [np.asarray(t, dtype=float) for t in ts]
    if not xyzs:
        return []
    n = np.array([len(t) for t in ts])
    if any(x.shape != (len(t), 3) for x, t in zip(xyzs, ts, strict=True)) or (n < 2).any():
        return [repaired_xyz(x, t, policy) for x, t in zip(xyzs, ts, strict=True)]
    xyz, t = np.concatenate(xyzs), np.concatenate(ts)
    ends = np.cumsum(n)
    starts = ends - n
    finite = np.isfinite(xyz).all(axis=1)
    # done here: finite, no time step above gap_factor × the median step, long enough, spikes interpolated
    # or kept; the others go through repaired_xyz
    simple = np.logical_and.reduceat(finite, starts) & (n >= policy.min_piece)
    dev = None
    fixed = xyz
    if math.isfinite(policy.spike_threshold):
        if not finite.all() or policy.spikes == "drop":
            simple[:] = False
        else:
            dev = spike_deviations(xyzs, policy.spike_window)
            if policy.spikes == "interpolate":
                fixed = _interpolate_spikes(
                    xyz, t, np.concatenate(dev) > policy.spike_threshold, starts, ends
                )
    dt = np.diff(t)
    inner = np.ones(len(dt), dtype=bool)
    inner[ends[:-1] - 1] = False  # the steps between trajectories
    table = np.full((len(n), int(n.max()) - 1), np.inf)
    table[np.arange(len(n)).repeat(n - 1), np.concatenate([np.arange(k - 1) for k in n])] = dt[inner]
    table.sort(axis=1)
    lo, hi = (n - 2) // 2, (n - 1) // 2  # np.median: the middle value, or the mean of the middle two
    rows = np.arange(len(n))
    median = np.where(lo == hi, table[rows, lo], (table[rows, lo] + table[rows, hi]) / 2)
    largest = table[rows, n - 2]
    simple &= ~(largest > policy.gap_factor * median) & (table[:, 0] > 0) & np.isfinite(largest)
    return [
        fixed[starts[i] : ends[i]]
        if simple[i]
        else repaired_xyz(xyzs[i], ts[i], policy, None if dev is None else dev[i])
        for i in range(len(n))
    ]


def _interpolate_spikes(
    xyz: np.ndarray, t: np.ndarray, spikes: np.ndarray, starts: np.ndarray, ends: np.ndarray
) -> np.ndarray:
    """The spikes of each trajectory replaced by linear interpolation in time from its other frames.

    What ``np.interp(t[spikes], t[good], xyz[good, k])`` gives, trajectory by trajectory (a trajectory
    with fewer than two other frames keeps its spikes, as :func:`~glu.gestures.trajectories.repair`):
    between two good frames ``slope · (t − t_j) + y_j`` with ``slope = (y_{j+1} − y_j) / (t_{j+1} − t_j)``,
    before the first good frame its value, after the last its value.
    """
    good = ~spikes
    n_good = np.add.reduceat(good.astype(np.int64), starts)
    owner = np.repeat(np.arange(len(starts)), ends - starts)
    todo = spikes & (n_good >= 2)[owner]
    if not todo.any():
        return xyz
    i = np.arange(len(t))
    prev = np.maximum.accumulate(np.where(good, i, -1))
    nxt = np.minimum.accumulate(np.where(good, i, len(t))[::-1])[::-1]
    s = np.flatnonzero(todo)
    own = owner[s]
    p, q = prev[s], nxt[s]
    has_p, has_q = p >= starts[own], q < ends[own]
    p, q = np.where(has_p, p, q), np.where(has_q, q, p)
    both = has_p & has_q
    with np.errstate(divide="ignore", invalid="ignore"):  # p == q where one side has no good frame
        slope = (xyz[q] - xyz[p]) / (t[q] - t[p])[:, None]
        value = slope * (t[s] - t[p])[:, None] + xyz[p]
    out = xyz.copy()
    out[s] = np.where(both[:, None], value, xyz[p])
    return out
