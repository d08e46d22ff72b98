"""The world of simulated human–robot episodes, shared by the corpus evaluation and learning from effects.

An episode is one person acting on one object in front of the robot. What this module holds is what both
simulators agree on: which objects people act on and how often each action is performed (:class:`Scenario`,
:data:`ACTION_PRIORS`), how the robot sees the person (:class:`Condition`: sensor noise and a viewpoint of
:data:`VIEWPOINTS`), the gesture generator's tracking problems (:class:`GestureSettings`), and the spawn keys
that make an episode's draws the same whatever machine simulates it. The corpus evaluation simulates its
episodes in :mod:`glu.studies.corpus_evaluation.corpus`, learning from effects in
:mod:`glu.studies.learning.self_supervised`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from glu.errors import DataError
from glu.gestures.synthetic import View
from glu.schema import AFFORDANCE_VALUES, ROOT_NODES

EFFECT_NODES: tuple[str, ...] = ("ObjVel", "ObjHandVel", "HandVel", "Contact")
"""The nodes the network draws (with the words) once the scenario has set the roots."""
VIEWPOINTS: dict[str, View] = {
    "front": View(),
    "turned": View(yaw_deg=40.0),
    "seated": View(posture="seated"),
}
"""Named viewpoints: as in the recordings (facing the camera, turned by a random ± 10°), turned by 40°,
seated at a higher table (:class:`~glu.gestures.synthetic.View`)."""
WORLD_KEY, GESTURE_KEY = 0, 1
"""Spawn keys of the world draws (per chunk) and of each episode's gesture (per episode)."""
ACTION_PRIORS: dict[str, str] = {
    "uniform": "every action equally often",
    "network": "as often as the network's prior p(Action) says (the robot's own experiments)",
    "scenario": "with the weights of [scenario.Action]",
}
"""How often each action is performed in the episodes."""


@dataclass(frozen=True)
class Scenario:
    """Which objects people act on and how: a distribution over each root node, independent of the others.

    Attributes
    ----------
    weights : root node (Action, Color, Shape, Size) → weights over its values in the schema's order
        (normalised; a node left out is uniform). The Action weights apply to conditions whose action
        prior is ``scenario`` (:data:`ACTION_PRIORS`)
    """

    weights: Mapping[str, tuple[float, ...]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for node, w in self.weights.items():
            if node not in ROOT_NODES:
                raise DataError(f"scenario: {node!r} is not a root node; allowed: {', '.join(ROOT_NODES)}")
            k = len(AFFORDANCE_VALUES[node])
            w = np.asarray(w, dtype=float)
            if w.shape != (k,) or not np.all(np.isfinite(w)) or (w < 0).any() or w.sum() <= 0:
                raise DataError(
                    f"scenario: {node} needs {k} non-negative weights ({', '.join(AFFORDANCE_VALUES[node])}) "
                    "with a positive sum"
                )

    @classmethod
    def from_mapping(cls, spec: Mapping[str, Mapping[str, float]]) -> Scenario:
        """From ``{node: {value: weight}}`` (values left out weigh 0; a node left out is uniform)."""
        weights = {}
        for node, by_value in spec.items():
            if node not in ROOT_NODES:
                raise DataError(f"scenario: {node!r} is not a root node; allowed: {', '.join(ROOT_NODES)}")
            if not isinstance(by_value, Mapping):
                raise DataError(f"scenario: {node} must map values to weights, e.g. {{tap = 2, grasp = 1}}")
            values = AFFORDANCE_VALUES[node]
            unknown = [v for v in by_value if v not in values]
            if unknown:
                raise DataError(f"scenario: {node} has no value {unknown[0]!r}; allowed: {', '.join(values)}")
            bad = [v for v, x in by_value.items() if isinstance(x, bool) or not isinstance(x, int | float)]
            if bad:
                raise DataError(f"scenario: the weight of {node}={bad[0]} must be a number")
            weights[node] = tuple(float(by_value.get(v, 0.0)) for v in values)
        return cls(weights)

    def probabilities(self, node: str) -> np.ndarray:
        """The distribution of a root node, shape (n_values,)."""
        w = np.asarray(self.weights.get(node, np.ones(len(AFFORDANCE_VALUES[node]))), dtype=float)
        return w / w.sum()

    def as_dict(self) -> dict[str, dict[str, float]]:
        """``{node: {value: probability}}`` for every root node."""
        return {
            n: dict(zip(AFFORDANCE_VALUES[n], self.probabilities(n).round(12).tolist(), strict=True))
            for n in ROOT_NODES
        }


@dataclass(frozen=True)
class Condition:
    """How the episodes are drawn (the action prior) and how the robot sees them (sensor noise, viewpoint).

    Attributes
    ----------
    noise : standard deviation of the sensor noise on every joint, metres
    viewpoint : a name of :data:`VIEWPOINTS` (or of ``views`` given to :func:`simulate_chunk`)
    action_prior : a name of :data:`ACTION_PRIORS`
    """

    noise: float
    viewpoint: str
    action_prior: str = "uniform"

    def __post_init__(self) -> None:
        if not (isinstance(self.noise, int | float) and 0 <= self.noise < math.inf):
            raise DataError(f"noise={self.noise!r}: the sensor noise must be a number ≥ 0 (metres)")
        if self.action_prior not in ACTION_PRIORS:
            raise DataError(
                f"unknown action prior {self.action_prior!r}; allowed: {', '.join(ACTION_PRIORS)}"
            )


@dataclass(frozen=True)
class GestureSettings:
    """The gesture generator's tracking problems (the person's speed, amplitude and size it draws itself).

    Attributes
    ----------
    spike_rate : probability that a frame's hand joint is an outlier
    dropout_rate : probability that an episode loses a run of 3–20 frames (a tracking gap)
    """

    spike_rate: float = 0.005
    dropout_rate: float = 0.2

    def __post_init__(self) -> None:
        for name in ("spike_rate", "dropout_rate"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and 0 <= v <= 1):
                raise DataError(f"{name}={v!r}: must be a probability in [0, 1]")
