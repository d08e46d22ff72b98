"""The world of simulated human–robot episodes, shared by the corpus evaluation and learning from effects.

An episode is one person acting on one object in front of the robot. What this module holds is what both
simulators agree on: which objects people act on and how often each action is performed (:class:`Scenario`,
:data:`ACTION_PRIORS`), how the robot sees the person (:class:`Condition`: sensor noise and a viewpoint of
:data:`VIEWPOINTS`), the gesture generator's tracking problems (:class:`GestureSettings`), and the spawn keys
that make an episode's draws the same whatever machine simulates it. The corpus evaluation simulates its
episodes in :mod:`glu.studies.corpus_evaluation.corpus`, learning from effects in
:mod:`glu.studies.learning.self_supervised`.

**Effects that depend on the gesture.** The fusion rules assume that the gesture tells nothing about the
effect beyond the action (G ⟂ effects | action). By default the world obeys it: the effects are drawn from
the network given the action and the object alone. :class:`GestureEffects` breaks it on purpose, in the
way a real table does: a fast tap sends the object further, and the taps that fail to move it are the
slow ones. :func:`gesture_speed` reads how fast each episode's gesture is (its amplitude over its
duration, as the gesture generator drew them, and the quantile of that speed among all the generator's
gestures); :func:`effects_given_gesture` redraws the effects of the episodes it concerns, and everything
the network draws below them (the other effects given them, the words), from those speeds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from glu.bn.inference import Engine
from glu.bn.sampling import categorical, sample
from glu.errors import DataError
from glu.gestures.synthetic import View
from glu.schema import AFFORDANCE_VALUES, ROOT_NODES

EFFECT_NODES: tuple[str, ...] = ("ObjVel", "ObjHandVel", "HandVel", "Contact")
"""The nodes the network draws (with the words) once the scenario has set the roots."""
VIEWPOINTS: dict[str, View] = {
    "front": View(),
    "turned": View(yaw_deg=40.0, tracker="occluding"),
    "side-on": View(yaw_deg=90.0, tracker="occluding"),
    "seated": View(posture="seated"),
}
"""Named viewpoints (:class:`~glu.gestures.views.View`): as in the recordings (facing the camera, turned by
a random ± 10°), turned by 40°, side-on (turned by 90°), seated at a higher table. The turned views are seen
through the occluding tracker (:func:`glu.gestures.views.track`), which sees both shoulders at 40° and
loses the far one side-on."""
WORLD_KEY, GESTURE_KEY, EFFECTS_KEY = 0, 1, 6
"""Spawn keys of the world draws (per chunk), of each episode's gesture (per episode), and of the effects
redrawn from the gestures (per chunk, :func:`effects_given_gesture`)."""
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
    effects : a name of :data:`GESTURE_WORLDS`: whether the effects depend on the action alone (the fusion
        rules' assumption) or on the gesture too
    """

    noise: float
    viewpoint: str
    action_prior: str = "uniform"
    effects: str = "action"

    def __post_init__(self) -> None:
        if not (isinstance(self.noise, int | float) and 0 <= self.noise < math.inf):
            raise DataError(f"noise={self.noise!r}: the sensor noise must be a number ≥ 0 (metres)")
        if self.action_prior not in ACTION_PRIORS:
            raise DataError(
                f"unknown action prior {self.action_prior!r}; allowed: {', '.join(ACTION_PRIORS)}"
            )
        if self.effects not in GESTURE_WORLDS:
            raise DataError(f"unknown effects {self.effects!r}; allowed: {', '.join(GESTURE_WORLDS)}")


def check_probability(value: Any, name: str, where: str = "") -> None:
    """DataError unless ``value`` is a number in [0, 1]: ``[where: ]name=value: must be a probability in
    [0, 1]``."""
    if not (isinstance(value, int | float) and 0 <= value <= 1):
        raise DataError(f"{where + ': ' if where else ''}{name}={value!r}: must be a probability in [0, 1]")


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
            check_probability(getattr(self, name), name)


DURATION_S: tuple[float, float] = (2.5, 5.0)
"""The range the gesture generator draws a person's movement duration from (seconds), uniformly."""
AMPLITUDE: tuple[float, float] = (0.85, 1.15)
"""The ranges the gesture generator draws a person's movement duration (seconds) and amplitude (the
excursion from rest, scaled) from, uniformly (:mod:`glu.gestures.synthetic`)."""
_PERSON_DRAWS = 7
"""Numbers the generator draws for the person (size, position x y z, turn, sway phase and amplitude) before
the movement's duration and amplitude."""


class GestureSpeed(NamedTuple):
    """How fast each episode's gesture is, as the generator drew it (the same in every noise level and view).

    Attributes
    ----------
    duration : array, shape (n,), the movement's duration, seconds (without the rest before and after)
    amplitude : array, shape (n,), the movement's amplitude factor
    speed : array, shape (n,), ``amplitude / duration`` (per second)
    quantile : array, shape (n,), the fraction of the generator's gestures that are slower: uniform on
        [0, 1] over episodes, 0.5 a typical gesture, 0.9 one faster than nine in ten
    """

    duration: np.ndarray
    amplitude: np.ndarray
    speed: np.ndarray
    quantile: np.ndarray


def speed_quantile(speed: np.ndarray) -> np.ndarray:
    """P(A / D ≤ s) for A uniform on :data:`AMPLITUDE` and D on :data:`DURATION_S`, in closed form:
    ``(1 / |D|) ∫ clip((s d − a0) / (a1 − a0), 0, 1) dd``.

    ``speed``: array of any shape, e.g. (n,), amplitude factor per second (:class:`GestureSpeed`); the
    quantiles, in [0, 1], have the same shape.
    """
    (d0, d1), (a0, a1) = DURATION_S, AMPLITUDE
    s = np.maximum(np.asarray(speed, dtype=float), 1e-12)
    lo, hi = np.clip(a0 / s, d0, d1), np.clip(a1 / s, d0, d1)
    ramp = (s * (hi**2 - lo**2) / 2 - a0 * (hi - lo)) / (a1 - a0)
    return np.clip((ramp + (d1 - hi)) / (d1 - d0), 0.0, 1.0)


def gesture_speed(rngs: Sequence[np.random.Generator]) -> GestureSpeed:
    """How fast each gesture is, from fresh copies of the generators its gesture is drawn with.

    ``rngs[i]`` must be a generator in the state the gesture generator
    (:func:`glu.gestures.synthetic.synthesize_gesture`, or the corpus's batch of them) receives it for a
    person's gesture: the duration and amplitude are its 8th and 9th uniform numbers, after the person's
    (tested against the generator). The generators are advanced.
    """
    u = np.array([rng.random(_PERSON_DRAWS + 2)[_PERSON_DRAWS:] for rng in rngs]).reshape(-1, 2)
    (d0, d1), (a0, a1) = DURATION_S, AMPLITUDE
    duration = d0 + (d1 - d0) * u[:, 0]
    amplitude = a0 + (a1 - a0) * u[:, 1]
    speed = amplitude / duration
    return GestureSpeed(duration, amplitude, speed, speed_quantile(speed))


@dataclass(frozen=True)
class GestureEffects:
    """How the effects depend on the gesture as well as on the action (the fusion rules assume they do not).

    Attributes
    ----------
    speed_effect : how strongly the gesture's speed moves the effects of ``actions``: each node of
        ``nodes`` is redrawn from ``p(node | object, action) · exp(λ z r)``, where ``z = 2 q − 1`` is the
        gesture's speed quantile ``q`` put on [−1, 1] and ``r`` the value's rank put on [−1, 1] (slow −1,
        fast +1): a fast gesture makes the faster values likelier, a slow one the slower. 0: no effect
    failed_taps : the fraction of taps, the slowest, whose object does not move (ObjVel slow, as after a
        touch): a tap fails when its speed quantile is below this
    actions : the actions whose effects the speed changes
    nodes : the effect nodes the speed changes (ordered values, slowest first)
    """

    speed_effect: float = 0.0
    failed_taps: float = 0.0
    actions: tuple[str, ...] = ("tap",)
    nodes: tuple[str, ...] = ("ObjVel",)

    def __post_init__(self) -> None:
        if not (isinstance(self.speed_effect, int | float) and 0 <= self.speed_effect < math.inf):
            raise DataError(f"speed_effect={self.speed_effect!r}: must be a number ≥ 0")
        if not (isinstance(self.failed_taps, int | float) and 0 <= self.failed_taps <= 1):
            raise DataError(f"failed_taps={self.failed_taps!r}: must be a fraction in [0, 1]")
        for a in self.actions:
            if a not in AFFORDANCE_VALUES["Action"]:
                allowed = ", ".join(AFFORDANCE_VALUES["Action"])
                raise DataError(f"gesture effects: unknown action {a!r}; allowed: {allowed}")
        for node in self.nodes:
            if node not in EFFECT_NODES:
                allowed = ", ".join(EFFECT_NODES)
                raise DataError(f"gesture effects: {node!r} is not an effect node; allowed: {allowed}")

    @property
    def active(self) -> bool:
        """Whether the effects depend on the gesture at all."""
        return self.speed_effect > 0 or self.failed_taps > 0


GESTURE_WORLDS: dict[str, GestureEffects] = {
    "action": GestureEffects(),
    "gesture": GestureEffects(speed_effect=2.0, failed_taps=0.25),
}
"""Named worlds: the effects depend on the action alone (the fusion rules' assumption), or also on the
gesture — a fast tap sends the object further (λ = 2: the fastest taps' ObjVel is about e² times likelier
fast and e² times less likely slow than the network says), and the slowest quarter of the taps fail."""


def effects_given_gesture(
    engine: Engine,
    codes: Mapping[str, np.ndarray],
    quantile: np.ndarray,
    effects: GestureEffects,
    rng: np.random.Generator,
) -> dict[str, np.ndarray]:
    """The episodes' values with the effects redrawn from their gestures' speeds, where ``effects`` says.

    Each node of ``effects.nodes`` of the episodes of ``effects.actions`` is drawn from the tilted
    p(node | object, action[, the nodes before it]) (:class:`GestureEffects`); then the slowest taps'
    ObjVel is set slow. Episodes whose effect nodes changed get the rest of the network (the other effects,
    the words) drawn again given their roots and new effects (:func:`glu.bn.sampling.sample`, which
    conditions on them); the others keep every value.

    Parameters
    ----------
    engine : the network the episodes were drawn from
    codes : node → int array, shape (n,), every node's value index (as :func:`glu.bn.sampling.sample`
        returns them)
    quantile : array, shape (n,), each gesture's speed quantile (:attr:`GestureSpeed.quantile`)
    effects : how the effects depend on the gesture; inactive: ``codes`` returned unchanged, ``rng``
        untouched
    rng : the generator of the new draws
    """
    out = {k: np.asarray(v, dtype=np.intp).copy() for k, v in codes.items()}
    if not effects.active:
        return out
    schema = engine.bn.schema
    quantile = np.asarray(quantile, dtype=float)
    acts = [schema.values_of("Action").index(a) for a in effects.actions]
    moved = np.isin(out["Action"], acts)
    roots = list(schema.root_nodes)
    evidence = {r: out[r] for r in roots}
    if effects.speed_effect > 0 and moved.any():
        rows = np.flatnonzero(moved)
        z = 2 * quantile[rows] - 1
        for node in effects.nodes:
            p = engine.query_batch([node], {k: v[rows] for k, v in evidence.items()})[node]
            k = p.shape[1]
            rank = np.linspace(-1.0, 1.0, k) if k > 1 else np.zeros(1)
            tilted = p * np.exp(effects.speed_effect * z[:, None] * rank[None, :])
            out[node][rows] = categorical(tilted, rng)
            evidence = {**evidence, node: out[node]}
    if effects.failed_taps > 0 and "tap" in schema.values_of("Action"):
        fails = (out["Action"] == schema.values_of("Action").index("tap")) & (quantile < effects.failed_taps)
        out["ObjVel"][fails] = schema.values_of("ObjVel").index("slow")
    redrawn = set(effects.nodes) | {"ObjVel"}
    rows = np.flatnonzero(np.any([out[node] != np.asarray(codes[node]) for node in redrawn], axis=0))
    if len(rows):
        fixed = {node: out[node][rows] for node in [*roots, *redrawn]}
        for node, v in sample(engine, fixed, rng).items():
            out[node][rows] = v
    return out
