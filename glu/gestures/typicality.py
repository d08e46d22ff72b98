"""Does a gesture look like anything the models know? Its per-frame log-likelihood against a reference range.

The posterior ``p_HMM(A | G)`` always sums to 1, even for a trajectory no model explains (a different
sensor, another unit, a person seen from behind): the least implausible model then wins with p ≈ 1. The
per-frame log-likelihood ``log L(G | a*) / T`` of the winning model ``a*`` says how plausible the gesture
is at all. Each recogniser keeps, per action, the range of that number over reference sequences:

* for a recogniser trained by glu, its **training sequences** (:func:`training_range`, saved in the file);
* for the originals' 2013 models, whose training data is not published, **sequences sampled from each
  model** (:func:`sampled_range`, seeded).

:func:`check` flags a gesture whose value lies farther outside its action's range than the range is wide
(at least :data:`MIN_MARGIN` nats per frame): ``glu recognize`` then warns, and says so in ``--json``.

The likelihood misses two realistic mistakes, so :class:`FeatureRanges` looks at the hand features
themselves, against where the reference gestures start and how far they move (kept in the recogniser's
meta under :data:`FRAMES_KEY`):

* **a hand that does not move** — its largest extent along an axis is under :data:`STILL_FRACTION` of the
  smallest extent of a reference gesture (a frozen tracker, the wrong joint);
* **axes that do not fit the frame** (x right, y up, z back, torso-centred: ``docs/method.md`` §4.2) — where
  it starts (:func:`start_position`) lies farther outside where the reference gestures start, on some axis,
  than half their range is wide (at least :data:`MIN_START_MARGIN` units): axes swapped or mislabelled,
  another unit, or another posture.

>>> r = LoglikRange(low=-1.0, high=2.0, reference="training")
>>> r.outside(-10.5), r.outside(-20.0)
(False, True)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from glu.errors import ModelError
from glu.hmm import GestureHMM, loglik_many, stack_models

MIN_MARGIN = 15.0
"""Nats per frame: the smallest distance outside the range that counts as far. Measured on the real data
with the originals' models (sampled range about −0.6 … 1.1): the 13 published segments, from a person the
models never saw, reach −10.5; the same gestures in the wrong unit reach −16.7 (× 0.1), −20 (× 0.001),
−1946 (× 10) and −2.4·10⁷ (millimetres)."""
META_KEY = "per_frame_loglik"
"""Where a recogniser's meta keeps the ranges: action → [low, high], and ``reference``."""
FRAMES_KEY = "hand_features"
"""Where a recogniser's meta keeps the :class:`FeatureRanges` of its reference gestures."""
STILL_FRACTION = 0.05
"""A gesture moves too little when its extent is under this fraction of the reference gestures' smallest."""
MIN_START_MARGIN = 0.3
"""Feature units (the features are divided by body size, so about 10 cm): the least distance outside the
reference start positions that counts as far. On the real data the standing segments start within
y ∈ [−1.54, −1.13], z ∈ [0.0, 0.4]; the same segments with y and z swapped start 1.1 or more away."""
AXES = ("x", "y", "z")
START_FRAMES = 10
"""Where a gesture starts: the median of its first frames (at most this many, at most a tenth of them), so
that one tracking spike on the first frame does not move it."""


def start_position(X: np.ndarray) -> np.ndarray:
    """Where a gesture of shape (T, D) starts: the median of its first :data:`START_FRAMES` frames (at most
    a tenth of the gesture, at least one frame), shape (D,)."""
    X = np.asarray(X, dtype=float)
    k = max(1, min(START_FRAMES, len(X) // 10))
    return np.median(X[:k], axis=0)


@dataclass(frozen=True)
class LoglikRange:
    """Per-frame log-likelihoods seen for one action's reference sequences (nats per frame)."""

    low: float
    high: float
    reference: str

    @property
    def margin(self) -> float:
        """How far outside the range is far: the range's width, at least :data:`MIN_MARGIN`."""
        return max(self.high - self.low, MIN_MARGIN)

    def outside(self, per_frame: float) -> bool:
        """True if ``per_frame`` lies more than :attr:`margin` below ``low`` or above ``high``."""
        return bool(
            not np.isfinite(per_frame)
            or per_frame < self.low - self.margin
            or per_frame > self.high + self.margin
        )


@dataclass(frozen=True)
class FeatureRanges:
    """Where reference gestures start, and how far the least of them moves (hand features, model units).

    Attributes
    ----------
    start_low, start_high : per axis, the lowest and highest first frame of the reference gestures
    extent_low : the smallest extent of a reference gesture (its largest range along one axis)
    reference : ``"training"`` or ``"sampled"``
    """

    start_low: tuple[float, ...]
    start_high: tuple[float, ...]
    extent_low: float
    reference: str

    @classmethod
    def of(cls, sequences: Sequence[np.ndarray], reference: str) -> FeatureRanges:
        """The ranges of ``sequences``, each of shape (T_i, D)."""
        starts = np.array([start_position(X) for X in sequences])
        extent = min(float(np.ptp(np.asarray(X, dtype=float), axis=0).max()) for X in sequences)
        return cls(tuple(starts.min(0).tolist()), tuple(starts.max(0).tolist()), extent, reference)

    def problems(self, X: np.ndarray) -> list[str]:
        """What does not fit, one phrase each (empty if the gesture fits), for ``X`` of shape (T, D)."""
        X = np.asarray(X, dtype=float)
        out = []
        extent = float(np.ptp(X, axis=0).max())
        if extent < STILL_FRACTION * self.extent_low:
            out.append(
                f"the hand hardly moves (extent {extent:.3g} units; every {self.reference} gesture moves at "
                f"least {self.extent_low:.3g})"
            )
        far = []
        for d, (v, lo, hi) in enumerate(
            zip(start_position(X).tolist(), self.start_low, self.start_high, strict=True)
        ):
            margin = max(0.5 * (hi - lo), MIN_START_MARGIN)
            if v < lo - margin or v > hi + margin:
                name = AXES[d] if len(self.start_low) == len(AXES) else f"axis {d + 1}"
                far.append(f"{name} = {v:.2f} (they start in {lo:.2f} … {hi:.2f})")
        if far:
            out.append(
                f"it starts far from where the {self.reference} gestures start: {'; '.join(far)} — "
                "axes swapped or mislabelled, another unit, or another posture?"
            )
        return out

    def to_meta(self) -> dict[str, Any]:
        """The ranges as a recogniser's meta entry (JSON)."""
        return {**asdict(self), "start_low": list(self.start_low), "start_high": list(self.start_high)}

    @classmethod
    def from_meta(cls, meta: Mapping[str, Any]) -> FeatureRanges | None:
        """The ranges saved by :meth:`to_meta` under :data:`FRAMES_KEY`, or None when there are none."""
        entry = meta.get(FRAMES_KEY)
        if entry is None:
            return None
        try:
            low, high = [float(v) for v in entry["start_low"]], [float(v) for v in entry["start_high"]]
            extent = float(entry["extent_low"])
            ok = len(low) == len(high) > 0 and all(np.isfinite(low + high + [extent]))
            ok = ok and extent >= 0 and all(a <= b for a, b in zip(low, high, strict=True))
        except (TypeError, KeyError, ValueError):
            ok = False
        if not ok:
            raise ModelError(
                f"meta.{FRAMES_KEY}: expected start_low, start_high (finite, low ≤ high), extent_low"
            )
        return cls(tuple(low), tuple(high), extent, str(entry.get("reference", "training")))


@dataclass(frozen=True)
class Typicality:
    """The verdict on one gesture: the winning action, its per-frame log-likelihood and its range, and what
    else does not fit (:meth:`FeatureRanges.problems`)."""

    action: str
    per_frame: float
    range: LoglikRange
    outside: bool
    problems: tuple[str, ...] = ()

    @property
    def atypical(self) -> bool:
        """True if anything does not fit: the likelihood, the motion or the frame."""
        return self.outside or bool(self.problems)

    def distance(self) -> float:
        """How far (nats per frame) the per-frame log-likelihood lies outside its range; 0 inside it."""
        r = self.range
        return max(r.low - self.per_frame, self.per_frame - r.high, 0.0)

    def _where(self) -> str:
        """Where the per-frame log-likelihood lies against its range, with the distance and the margin."""
        r = self.range
        span = f"the {r.reference} range {r.low:.2f} … {r.high:.2f}"
        d = self.distance()
        if d == 0:
            return f"lies inside {span}"
        side = "below" if self.per_frame < r.low else "above"
        return f"lies {d:.2f} nats/frame {side} {span} (far means more than {r.margin:.2f})"

    def message(self) -> str:
        """One line for the person at the keyboard: the verdict, with how far outside its range the gesture
        lies and how far counts as far."""
        head = f"per-frame log L {self.per_frame:.2f} under {self.action} {self._where()}"
        if not self.atypical:
            return head
        what = list(self.problems)
        if self.outside:
            what.insert(0, head)
        return (
            f"warning: {'; '.join(what)}: the gesture looks like nothing the models were trained on (units, "
            "frame of reference, sensor?); the posterior is not meaningful"
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready fields (finite numbers only)."""
        return {
            "action": self.action,
            "per_frame_loglik": float(self.per_frame) if np.isfinite(self.per_frame) else None,
            "reference_range": [self.range.low, self.range.high],
            "reference": self.range.reference,
            "outside": self.outside,
            "problems": list(self.problems),
            "atypical": self.atypical,
        }


def _range(values: Sequence[float], reference: str) -> LoglikRange:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return LoglikRange(float(v.min()), float(v.max()), reference)


def training_range(model: GestureHMM, sequences: Sequence[np.ndarray]) -> LoglikRange:
    """The range of ``log L(X | model) / T`` over the training sequences, shape (T_i, D) each."""
    loglik = loglik_many(stack_models([model]), sequences)[:, 0]
    return _range([ll / len(X) for ll, X in zip(loglik.tolist(), sequences, strict=True)], "training")


def sampled_range(model: GestureHMM, n: int = 30, length: int = 60, seed: int = 0) -> LoglikRange:
    """The range over ``n`` sequences of ``length`` frames sampled from the model itself (seeded)."""
    return _range([model.loglik(X) / length for X in sampled_sequences(model, n, length, seed)], "sampled")


def ranges_to_meta(ranges: Mapping[str, LoglikRange]) -> dict[str, Any]:
    """The ranges as a recogniser's meta entry (JSON)."""
    ref = {r.reference for r in ranges.values()}
    return {
        "reference": ref.pop() if len(ref) == 1 else "mixed",
        **{a: [r.low, r.high] for a, r in ranges.items()},
    }


def ranges_from_meta(meta: Mapping[str, Any]) -> dict[str, LoglikRange] | None:
    """The ranges saved by :func:`ranges_to_meta`, or None when the recogniser has none."""
    entry = meta.get(META_KEY)
    if not isinstance(entry, Mapping):
        return None
    ref = str(entry.get("reference", "training"))
    out = {}
    for a, v in entry.items():
        if a == "reference":
            continue
        ok = isinstance(v, list | tuple) and len(v) == 2
        ok = ok and all(isinstance(x, int | float) and not isinstance(x, bool) and np.isfinite(x) for x in v)
        if not ok or v[0] > v[1]:
            raise ModelError(f"meta.{META_KEY}.{a}: expected [low, high], two finite numbers, not {v!r}")
        out[a] = LoglikRange(float(v[0]), float(v[1]), ref)
    return out or None


def check(
    loglik: np.ndarray,
    n_frames: int,
    actions: Sequence[str],
    ranges: Mapping[str, LoglikRange],
    X: np.ndarray | None = None,
    frames: FeatureRanges | None = None,
) -> Typicality:
    """The verdict for a gesture of ``n_frames`` frames with ``log L(G | a)`` per action, shape (n_actions,);
    with its hand features ``X`` (shape (T, D)) and the reference :class:`FeatureRanges`, also its motion
    and its frame."""
    k = int(np.argmax(loglik))
    per_frame = float(loglik[k]) / max(n_frames, 1)
    r = ranges[actions[k]]
    problems = tuple(frames.problems(X)) if frames is not None and X is not None else ()
    return Typicality(actions[k], per_frame, r, r.outside(per_frame), problems)


def sampled_sequences(model: GestureHMM, n: int = 30, length: int = 60, seed: int = 0) -> list[np.ndarray]:
    """``n`` sequences of ``length`` frames sampled from the model itself (seeded), shape (length, D) each."""
    rng = np.random.default_rng(seed)
    return [model.sample(length, seed=int(rng.integers(2**31 - 1))) for _ in range(n)]
