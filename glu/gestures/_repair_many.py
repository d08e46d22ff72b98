"""The repair of many trajectories at once (:func:`glu.gestures.trajectories.repair`), bit for bit.

A simulated corpus repairs every one of a million synthetic gestures, most of which need nothing done:
no spike, no gap. :func:`repaired_many` finds those for all trajectories together — the running
medians of the spike check in one pass over all frames (:func:`spike_deviations`), every frame period
by one sort — returns their coordinates untouched, and repairs the others one by one with
:func:`~glu.gestures.trajectories.repaired_xyz` (the same code as :func:`~glu.gestures.trajectories.repair`).

Example
-------
>>> import numpy as np
>>> from glu.gestures.trajectories import Trajectory, repair
>>> rng = np.random.default_rng(0)
>>> xyz = [rng.normal(size=(n, 3)) for n in (5, 40, 90)]
>>> t = [np.arange(n) / 30.0 for n in (5, 40, 90)]
>>> fast = repaired_many(xyz, t, min_piece=1)
>>> slow = [repair(Trajectory.from_array(x), RepairPolicy(min_piece=1)).pieces[0].xyz for x in xyz]
>>> all(np.array_equal(a, b) for a, b in zip(fast, slow))
True
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from glu.errors import DataError
from glu.gestures.trajectories import DEFAULT_POLICY, RepairPolicy, repaired_xyz


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
