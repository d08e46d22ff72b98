"""Feature sets: the frame the hand is measured in, and the invariances applied to it, under one name.

A recogniser sees the hand relative to the torso (:mod:`glu.gestures.features`) either in the torso's frame
(the originals') or in the body frame of the shoulder line (``body``,
:func:`glu.gestures.features.to_body_frame`, which needs the shoulders), and then applies any invariances
(:class:`~glu.gestures.invariants.Invariants`). A feature set names both: ``"raw"``, ``"centred+rotated"``,
``"body"``, ``"body+centred"``. The correspondence study (notebook 10) compares them; the corpus evaluation
(notebook 11) takes one or several as a setting of its recognisers.

Example
-------
>>> f = FeatureSet.parse("body+centred")
>>> f.body, f.invariants.names
(True, ('centred',))
>>> FeatureSet.parse("centred,rotated").name, FeatureSet.parse("body").name
('centred+rotated', 'body')
"""

from __future__ import annotations

from typing import Any, NamedTuple

from glu.gestures.invariants import FEATURE_NAMES, Invariants

BODY = "body"
"""The part of a feature set's name that puts it in the shoulder line's frame."""
FEATURE_SET_NAMES: tuple[str, ...] = (
    *FEATURE_NAMES,
    BODY,
    *(f"{BODY}+{n}" for n in FEATURE_NAMES if n != "raw"),
)
"""Every feature set: those of :data:`glu.gestures.invariants.FEATURE_NAMES`, and each in the shoulder line's
frame."""


class FeatureSet(NamedTuple):
    """Where the hand is measured (``body``: the shoulder line's frame, else the torso's), and its
    invariances."""

    body: bool
    invariants: Invariants

    @classmethod
    def parse(cls, name: str, **settings: Any) -> FeatureSet:
        """``"body+centred"`` → FeatureSet(True, centred) (``settings``: those of :class:`Invariants`)."""
        parts = [p.strip() for p in str(name).replace(",", "+").split("+") if p.strip()]
        body = BODY in parts
        rest = [p for p in parts if p != BODY]
        return cls(body, Invariants.parse("+".join(rest) if rest else "raw", **settings))

    @property
    def name(self) -> str:
        """The inverse of :meth:`parse`: ``"body+centred"``, ``"body"``, ``"centred+rotated"``, ``"raw"``."""
        if not self.body:
            return self.invariants.name
        return BODY if self.invariants.is_raw else f"{BODY}+{self.invariants.name}"
