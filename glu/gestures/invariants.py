"""Invariant gesture features: the same action from another place, posture, body, viewpoint or hand.

The gesture features (:mod:`glu.gestures.features`) are the hand relative to the torso, x right, y up,
z towards the person's back. They change when the same action is made from another posture (a seated
person's hand starts and moves elsewhere in the torso frame), by a bigger or smaller body (the 2017 logs
were normalised by constants, not by the person's size), seen from another side (a person turned by ψ
about the vertical gives features rotated by ψ) or with the other hand (x → −x). :class:`Invariants`
removes any combination of these four differences, frame by frame, using only the frames seen so far, so
the streaming recogniser applies exactly what the batch one does. Write the raw frames ``g_1, g_2, …`` as
a start ``s_t`` and a displacement ``d_t = g_t − s_t``, where the start is the mean of the first
``anchor_frames`` frames (``k``; the mean of the frames so far until then: ``s_t = mean(g_1 … g_min(t,k))``,
so that sensor noise on one frame does not shift the whole sequence), and the horizontal part of a vector
``v`` as ``h(v) = (v_x, v_z)``:

``rotated`` — rotation about the vertical axis (the observer's viewpoint)
    The heading of the movement is fixed once the hand has moved ``lock_radius`` horizontally from its
    start: at the first frame ``t*`` with ``|h(d_t*)| ≥ ρ``, ``u = h(d_t*) / |h(d_t*)|``. From then on every
    vector is turned by the rotation ``R_u`` about y that takes ``u`` straight ahead (to −z):
    ``x' = −u_z x + u_x z``, ``z' = −u_x x − u_z z`` (y unchanged). Before ``t*`` the displacement is turned
    by its own current heading, i.e. it becomes ``(0, d_y, −|h(d_t)|)``, and the start is not turned
    (no heading is known yet). So start-centred features are exactly invariant to the turn at every
    frame; uncentred ones only from ``t*`` on.
``mirrored`` — a mirror image (the other hand; a person facing the robot instead of beside it)
    ``σ_t = −1`` if the start lies left of the torso (``x < 0`` of the start, turned as above when
    ``rotated`` is also chosen, i.e. left of the movement's heading), else ``+1``; x is multiplied by
    ``σ_t``. The features become those of a right hand. With ``rotated``, a mirror image and a turn
    together are undone exactly (start-centred); without it, only for turns that keep the start on the
    same side of the torso.
``centred`` — translation (posture, position of the hand at rest)
    Only the (turned, mirrored) displacement is kept: ``v_t = d_t``; the start is dropped. Otherwise
    ``v_t = start + d_t`` (both turned and mirrored as above).
``scaled`` — body size and amplitude
    ``v_t / max(min_scale, max_{τ ≤ t} |v_τ|)``: divided by the largest excursion so far (from the start
    if centred, from the torso otherwise), at least ``min_scale`` so that the first frames of a movement
    are not blown up. Exactly invariant to a change of size once the excursion exceeds ``min_scale``.
    Rotation and mirroring preserve lengths, so this commutes with them.

``raw`` (no invariance) leaves the features as they are. The order in which the names are given does not
matter: the operations are always applied as above (turn and mirror, then centre, then scale). Each frame
costs a few microseconds (:class:`InvariantStream`); ``benchmarks/bench_hmm.py`` measures it.

A sensitivity to know: everything is anchored on the first frames. A tracking spike among them shifts
(``centred``), or turns (``rotated``), the whole sequence by its share of the mean; repair a log first if its
first frames may hold outliers.

Example
-------
>>> import numpy as np
>>> inv = Invariants.parse("centred,rotated")
>>> inv.name
'centred+rotated'
>>> X = np.array([[1.0, 0.0, 0.0], [1.0, 0.1, -0.5], [0.6, 0.2, -1.0]])   # (T=3, D=3)
>>> inv.transform(X).round(3)                                           # first move: straight ahead
array([[ 0. ,  0. ,  0. ],
       [ 0. ,  0.1, -0.5],
       [-0.4,  0.2, -1. ]])
>>> turned = X @ np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]).T   # seen after a 90° turn
>>> bool(np.allclose(inv.transform(turned), inv.transform(X)))
True
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from itertools import combinations
from typing import Any

import numpy as np

from glu.errors import DataError, ModelError

INVARIANCES: tuple[str, ...] = ("centred", "scaled", "rotated", "mirrored")
"""The invariances, in the order in which their names are written (``centred+scaled+rotated+mirrored``)."""
INVARIANCE_MEANING: dict[str, str] = {
    "centred": "translation: the displacement from the first frame (posture, rest position)",
    "scaled": "body size and amplitude: divided by the largest excursion so far",
    "rotated": "rotation about the vertical axis: the movement's first heading turned straight ahead",
    "mirrored": "mirror image: reflected so that the hand starts right of the torso",
}
RAW = "raw"
"""The name of the features without any invariance."""
ALL = "all"
"""Shorthand for every invariance."""
FEATURE_NAMES: tuple[str, ...] = (
    RAW,
    *("+".join(c) for r in range(1, len(INVARIANCES) + 1) for c in combinations(INVARIANCES, r)),
    ALL,
)
"""Every feature set by its canonical name (``raw``, ``centred``, …, ``centred+scaled+rotated+mirrored``,
``all``)."""
LOCK_RADIUS = 0.4
"""Default ρ: horizontal distance from the start (feature units, about 13 cm) that fixes the heading."""
MIN_SCALE = 0.25
"""Default floor of the scale (feature units, about 8 cm)."""
ANCHOR_FRAMES = 1
"""Default k: the start is the first frame (k = 5, a sixth of a second, averages out sensor noise)."""
N_FEATURES = 3


def _rotation(ux: float, uz: float, x: float, z: float) -> tuple[float, float]:
    """``R_u (x, z)``: the rotation about y that takes the unit heading ``(ux, uz)`` to (0, −1)."""
    return -uz * x + ux * z, -ux * x - uz * z


@dataclass(frozen=True)
class Invariants:
    """Which invariances the gesture features get, and their two settings (see the module docstring).

    Attributes
    ----------
    names : the invariances, a subset of :data:`INVARIANCES` (stored in that order); empty = raw
    lock_radius : ρ, horizontal distance from the start that fixes the heading (feature units)
    min_scale : the floor of the scale (feature units)
    anchor_frames : k, the start is the mean of the first k frames
    """

    names: tuple[str, ...] = ()
    lock_radius: float = LOCK_RADIUS
    min_scale: float = MIN_SCALE
    anchor_frames: int = ANCHOR_FRAMES

    def __post_init__(self) -> None:
        names = tuple(self.names)
        bad = [n for n in names if n not in INVARIANCES]
        if bad:
            raise DataError(
                f"unknown invariance {bad[0]!r}; allowed: {', '.join(INVARIANCES)}, or {RAW} / {ALL}"
            )
        object.__setattr__(self, "names", tuple(n for n in INVARIANCES if n in names))
        for what, v in (("lock_radius", self.lock_radius), ("min_scale", self.min_scale)):
            if not (isinstance(v, int | float) and 0 < v < math.inf):
                raise DataError(f"{what}={v!r} must be a positive number (feature units)")
        if not (isinstance(self.anchor_frames, int) and self.anchor_frames >= 1):
            raise DataError(f"anchor_frames={self.anchor_frames!r} must be a whole number ≥ 1")

    @classmethod
    def parse(cls, text: str | Iterable[str] | Invariants | None, **settings: Any) -> Invariants:
        """``"centred,scaled"`` (or ``"centred+scaled"``, a list of names, ``"raw"``, ``"all"``) →
        Invariants."""
        if isinstance(text, Invariants):
            return text if not settings else cls(text.names, **settings)
        if text is None:
            return cls((), **settings)
        parts = text.replace("+", ",").split(",") if isinstance(text, str) else list(text)
        names = [p.strip() for p in parts if p.strip()]
        if not names and isinstance(text, str) and text.strip():  # " , ": a list of nothing, not "raw"
            raise DataError(
                f"{text!r}: no invariance named; give {RAW}, {ALL} or names among {', '.join(INVARIANCES)}"
            )
        if names == [ALL]:
            names = list(INVARIANCES)
        elif names in ([RAW], []):
            names = []
        if len(set(names)) != len(names):
            raise DataError(f"{text!r}: an invariance is named twice")
        return cls(tuple(names), **settings)

    @property
    def name(self) -> str:
        """``"raw"`` or the names joined by ``+``, e.g. ``"centred+rotated"``."""
        return "+".join(self.names) or RAW

    @property
    def is_raw(self) -> bool:
        """True when no invariance is applied."""
        return not self.names

    def describe(self) -> str:
        """One line: the name and what each invariance removes."""
        if self.is_raw:
            return "raw features (no invariance)"
        return "; ".join(INVARIANCE_MEANING[n] for n in self.names)

    def to_dict(self) -> dict[str, Any]:
        """What a recogniser file records:
        ``{"names": [...], "lock_radius": ρ, "min_scale": …, "anchor_frames": k}``."""
        return {**asdict(self), "names": list(self.names)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None, source: str = "<dict>") -> Invariants:
        """The inverse of :meth:`to_dict` (None → raw); :class:`ModelError` naming ``source`` if malformed."""
        if d is None:
            return cls()
        try:
            return cls(
                tuple(d["names"]),
                float(d.get("lock_radius", LOCK_RADIUS)),
                float(d.get("min_scale", MIN_SCALE)),
                int(d.get("anchor_frames", ANCHOR_FRAMES)),
            )
        except (KeyError, TypeError, ValueError, DataError) as e:
            raise ModelError(f"{source}: malformed invariant features ({e})") from None

    # ------------------------------------------------------------------ computing them

    def transform(self, X: np.ndarray) -> np.ndarray:
        """The invariant features of a whole sequence, shape (T, 3) → (T, 3) (a new array).

        Frame t depends only on frames 1 … t; the result equals pushing the frames one by one into
        :meth:`stream` (tested).
        """
        X = np.asarray(X, dtype=float)
        if X.ndim != 2 or X.shape[1] != N_FEATURES:
            raise DataError(f"invariant features need shape (n_frames, 3), got {X.shape}")
        if self.is_raw or len(X) == 0:
            return X.copy()
        names = self.names
        k = min(self.anchor_frames, len(X))
        start = np.empty_like(X)
        start[:k] = np.cumsum(X[:k], axis=0) / np.arange(1, k + 1)[:, None]
        start[k:] = start[k - 1]
        disp = X - start
        if "rotated" in names:
            radius = np.hypot(disp[:, 0], disp[:, 2])
            hit = np.flatnonzero(radius >= self.lock_radius)
            lock = int(hit[0]) if len(hit) else len(X)
            pre = slice(0, lock)
            disp[pre, 0], disp[pre, 2] = 0.0, 0.0 - radius[pre]  # 0 - r: no negative zero
            if lock < len(X):
                ux, uz = disp[lock, 0] / radius[lock], disp[lock, 2] / radius[lock]
                post = slice(lock, None)
                disp[post, 0], disp[post, 2] = _rotation(ux, uz, disp[post, 0], disp[post, 2])
                start[post, 0], start[post, 2] = _rotation(ux, uz, start[post, 0], start[post, 2])
        if "mirrored" in names:
            sigma = np.where(start[:, 0] < 0, -1.0, 1.0)
            disp[:, 0] *= sigma
            start[:, 0] *= sigma
        v = disp if "centred" in names else start + disp
        if "scaled" in names:
            v = v / np.maximum(self.min_scale, np.maximum.accumulate(np.linalg.norm(v, axis=1)))[:, None]
        return v

    def stream(self) -> InvariantStream:
        """A fresh :class:`InvariantStream`: the same features, one frame at a time."""
        return InvariantStream(self)


class InvariantStream:
    """The features of :class:`Invariants` computed frame by frame (O(1) state, a few µs per frame).

    Scalar arithmetic on Python floats: for one 3-vector this is several times faster than numpy calls.
    """

    def __init__(self, invariants: Invariants) -> None:
        self.invariants = invariants
        names = invariants.names
        self._centred = "centred" in names
        self._scaled = "scaled" in names
        self._rotated = "rotated" in names
        self._mirrored = "mirrored" in names
        self._rho = float(invariants.lock_radius)
        self._min_scale = float(invariants.min_scale)
        self._k = int(invariants.anchor_frames)
        self.reset()

    def reset(self) -> None:
        """Forget every frame: the next :meth:`push` is the first frame of a new gesture."""
        self._sum = [0.0, 0.0, 0.0]
        self._n = 0
        self._start = (0.0, 0.0, 0.0)
        self._u: tuple[float, float] | None = None
        self._scale = self._min_scale

    @property
    def heading(self) -> tuple[float, float] | None:
        """The locked heading ``u = (u_x, u_z)`` (``rotated``), or None before the lock."""
        return self._u

    def push(self, x: Sequence[float] | np.ndarray) -> np.ndarray:
        """The invariant features of the next frame, shape (3,) → (3,)."""
        gx, gy, gz = float(x[0]), float(x[1]), float(x[2])
        if self._n < self._k:
            sm = self._sum
            sm[0] += gx
            sm[1] += gy
            sm[2] += gz
            self._n += 1
            self._start = (sm[0] / self._n, sm[1] / self._n, sm[2] / self._n)
        sx, sy, sz = self._start
        dx, dy, dz = gx - sx, gy - sy, gz - sz
        if self._rotated:
            if self._u is None:
                r = math.hypot(dx, dz)
                if r >= self._rho:
                    self._u = (dx / r, dz / r)
                else:
                    dx, dz = 0.0, 0.0 - r
            if self._u is not None:
                ux, uz = self._u
                dx, dz = -uz * dx + ux * dz, -ux * dx - uz * dz
                sx, sz = -uz * sx + ux * sz, -ux * sx - uz * sz
        if self._mirrored and sx < 0:
            dx, sx = -dx, -sx
        if not self._centred:
            dx, dy, dz = sx + dx, sy + dy, sz + dz
        if self._scaled:
            n = math.sqrt(dx * dx + dy * dy + dz * dz)
            if n > self._scale:
                self._scale = n
            dx, dy, dz = dx / self._scale, dy / self._scale, dz / self._scale
        return np.array((dx, dy, dz))
