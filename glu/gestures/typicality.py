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

>>> r = LoglikRange(low=-1.0, high=2.0, reference="training")
>>> r.outside(-10.5), r.outside(-20.0)
(False, True)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
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
class Typicality:
    """The verdict on one gesture: the winning action, its per-frame log-likelihood and its range."""

    action: str
    per_frame: float
    range: LoglikRange
    outside: bool

    def message(self) -> str:
        """One line for the person at the keyboard."""
        r = self.range
        where = f"the {r.reference} range {r.low:.2f} … {r.high:.2f}"
        if not self.outside:
            return f"per-frame log L {self.per_frame:.2f} under {self.action} is within reach of {where}"
        return (
            f"warning: per-frame log L {self.per_frame:.2f} under {self.action} is far outside {where}: the "
            "gesture looks like nothing the models were trained on (units, frame of reference, sensor?); "
            "the posterior is not meaningful"
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready fields (finite numbers only)."""
        return {
            "action": self.action,
            "per_frame_loglik": float(self.per_frame) if np.isfinite(self.per_frame) else None,
            "reference_range": [self.range.low, self.range.high],
            "reference": self.range.reference,
            "outside": self.outside,
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
    hmm = model.to_hmmlearn()
    rng = np.random.default_rng(seed)
    values = []
    for _ in range(n):
        X, _ = hmm.sample(length, random_state=int(rng.integers(2**31 - 1)))
        values.append(model.loglik(X) / length)
    return _range(values, "sampled")


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
    loglik: np.ndarray, n_frames: int, actions: Sequence[str], ranges: Mapping[str, LoglikRange]
) -> Typicality:
    """The verdict for a gesture of ``n_frames`` frames with ``log L(G | a)`` per action, shape (n_actions,)."""
    k = int(np.argmax(loglik))
    per_frame = float(loglik[k]) / max(n_frames, 1)
    r = ranges[actions[k]]
    return Typicality(actions[k], per_frame, r, r.outside(per_frame))
