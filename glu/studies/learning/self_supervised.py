"""Learning gestures from what people's actions did: the robot labels what it sees with its affordance
network.

TCDS 2020 (§III-B): "If the human performs an unknown action on a spherical object and obtains a high
velocity, the robot will be able to infer that the action is most probably a tap … This information can
be used to train our statistical gesture recognition system." Here the robot watches **episodes** — a
person's hand trajectory, the object, the effect and, optionally, the words someone said — without the
action's name, labels each with its Affordance–Words network, ``p_BN(Action | object, effect[, words])``,
and trains its gesture HMMs from those labels (weighted EM, :func:`glu.hmm.train` with ``weights``).

* :class:`Ambiguity` — how well the effects tell the actions apart: the objects people act on, objects
  that never move, taps that fail (the object stays put, as after a touch), noisy perception of the effect.
  :data:`AMBIGUITIES` names the study's.
* :class:`World` — who the people are and how the robot sees them (sensor noise, people's own arm lengths and
  movement styles, turned views, body-frame features), and whether the effects depend on the gesture as well
  as on the action (:class:`glu.studies.episodes.GestureEffects`: a fast tap sends the object further, the
  slowest taps fail). :data:`WORLDS` names the study's: ``easy`` (the generator's people facing the camera,
  effects of the action alone) and ``hard``.
* :func:`simulate_episodes` — episodes drawn as the corpus draws them
  (:mod:`glu.studies.corpus_evaluation.corpus`): the action, then the person's gesture
  (:mod:`glu.gestures.synthetic`, one seeded generator per episode, the same in every ambiguity), the object,
  the effects and the words from the network (:func:`glu.bn.sampling.sample`), and what the robot perceives of
  the effect.
* :func:`network_posteriors` — ``p_BN(A | what the robot perceived)``, one row per episode.
* :func:`label_weights` — the labelling schemes (:data:`SCHEMES`): ``hard`` (the arg-max), ``soft`` (the
  posterior as weights), ``confident`` (the arg-max, only above a threshold), ``iterative`` (the product
  rule of the robot's current HMMs and the network, relabelled until the labels stop changing); and the
  baselines' labels (:data:`BASELINES`: the ``true`` action; ``unsupervised`` clusters); the controls
  (:data:`CONTROLS`: :func:`matched_random_labels`, clusters named by the network, semi-supervised EM; and
  :data:`SUPERVISED`, :func:`first_labels`).
* the learners themselves: all episodes at once in :mod:`glu.studies.learning.learned_recognizers`, one
  episode at a time in :mod:`glu.studies.learning.online`; the study in :mod:`glu.studies.learning.study`,
  the real person in :mod:`glu.studies.learning.real_person`.

Seeds: episode ``i`` of seed ``s`` has the same action and gesture in every ambiguity (the actions of a
stream numbered from ``offset`` come from ``(s, ACTION_KEY, offset)``, episode ``i``'s gesture from
``(s, GESTURE_KEY, i)``); the world (objects, effects, words) comes from ``(s, WORLD_KEY, offset)`` and the
perception noise from ``(s, PERCEPTION_KEY, offset)``, each person's turn in a turned world from ``(s,
VIEW_KEY, offset)``. Held-out episodes use ``offset`` = :data:`TEST_OFFSET`, never seen in training.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np

from glu.bn.inference import Engine
from glu.bn.sampling import categorical, sample
from glu.errors import DataError
from glu.gestures import calibration
from glu.gestures.synthetic import View
from glu.gestures.synthetic_batch import gesture_features
from glu.hmm import (
    TrainingConfig,
)
from glu.schema import AFFORDANCE_VALUES
from glu.studies.episodes import (
    GESTURE_KEY,
    GESTURE_WORLDS,
    WORLD_KEY,
    GestureEffects,
    GestureSettings,
    Scenario,
    check_probability,
    effects_given_gesture,
    gesture_speed,
)

SCHEMES: tuple[str, ...] = ("hard", "soft", "confident", "iterative")
"""How the robot labels an episode from its network (and, for ``iterative``, its current HMMs)."""
BASELINES: tuple[str, ...] = ("true", "unsupervised")
"""HMMs trained on the true labels (the upper bound) and on clusters matched to actions afterwards (the
lower bound). The third baseline, the network alone, recognises no gesture: its accuracy is that of its
labels."""
LEARNERS: tuple[str, ...] = SCHEMES + BASELINES
"""The learners that learn all episodes at once
(:func:`glu.studies.learning.learned_recognizers.learn_recognizer`, ``glu learn-gestures``) as well as
online."""
CONTROLS: tuple[str, ...] = ("random", "clustering", "em")
"""Controls that could explain learning from effects away, each beside the schemes in every condition
(online, :mod:`glu.studies.learning.online`): ``random`` — labels drawn at random, right as often as the
network's arg-max in that condition (:func:`matched_random_labels`), wrong uniformly; ``clustering`` — the
gestures clustered without labels, each cluster named after the fact by the network's posteriors of its
episodes (no true action); ``em`` — semi-supervised EM with the action latent, each episode weighted by
``p(A | gesture, object, effect) ∝ p(gesture | A) · p_BN(A | object, effect)`` (the likelihood itself, not
its per-frame reading)."""
SUPERVISED: tuple[int, ...] = (1, 5)
"""The ``supervised`` learners: the true labels of the first 1 and 5 episodes of each action, nothing
else (the true-label learner is supervision by every label)."""
ONLINE_LEARNERS: tuple[str, ...] = LEARNERS + CONTROLS + ("supervised",)
"""Every learner :func:`glu.studies.learning.online.run_online` runs."""
POSTERIOR_READINGS: tuple[str, ...] = ("likelihood", "per-frame")
"""How ``p_HMM`` is read from the likelihoods when the robot relabels (two
of :data:`glu.gestures.calibration.READINGS`)."""
ACTION_KEY, PERCEPTION_KEY, VIEW_KEY = 3, 4, 6
"""Spawn keys of the actions, of the perception noise and of each person's turn (the corpus uses 0 for the
world, 1 for gestures; the study's bootstrap 5)."""
TEST_OFFSET = 10_000_000
"""Held-out episodes are numbered from here (their gestures never meet a training episode's)."""
STUDY_TRAINING = TrainingConfig(n_states=6, n_mix=1, n_iter=50, tol=1e-3)
"""The study's HMMs: one Gaussian per state, short EM (as the correspondence study's)."""
OBSERVED_OBJECT: tuple[str, ...] = ("Color", "Shape", "Size")
EFFECTS: tuple[str, ...] = ("ObjVel",)
"""The effect the robot perceives by default: the object's velocity (TCDS's example)."""


def _by_name(*items: Any) -> dict[str, Any]:
    return {x.name: x for x in items}


@dataclass(frozen=True)
class Ambiguity:
    """How well the effects of the actions tell them apart.

    Attributes
    ----------
    name : a short name
    description : one line, for tables and figures
    objects : the distribution of actions and objects
        (:class:`~glu.studies.corpus_evaluation.corpus.Scenario`)
    still : the objects never move (ObjVel is slow whatever the action)
    failed_taps : the fraction of taps whose object does not move (ObjVel slow, as after a touch)
    perception_noise : the probability that the robot perceives an effect's value as a uniformly random one
    """

    name: str
    description: str = ""
    objects: Scenario = field(default_factory=Scenario)
    still: bool = False
    failed_taps: float = 0.0
    perception_noise: float = 0.0

    def __post_init__(self) -> None:
        for k in ("failed_taps", "perception_noise"):
            check_probability(getattr(self, k), k, f"ambiguity {self.name!r}")


AMBIGUITIES: dict[str, Ambiguity] = _by_name(
    Ambiguity(
        "spheres",
        "small and medium spheres: a tap rolls them, a touch does not",
        Scenario.from_mapping({"Shape": {"sphere": 1}, "Size": {"small": 1, "medium": 1}}),
    ),
    Ambiguity("mixed", "every object, as in the robot's experiments"),
    Ambiguity("still", "objects that never move", still=True),
    Ambiguity("failed_taps", "half of the taps fail: the object stays, as after a touch", failed_taps=0.5),
    Ambiguity("noisy", "the effect misperceived 30 % of the time", perception_noise=0.3),
)
"""The study's ambiguities, from effects that tell actions apart well to effects that mislead."""


@dataclass(frozen=True)
class World:
    """Who the people are, how the robot sees them, and what makes the effects.

    Attributes
    ----------
    name, description : as an :class:`Ambiguity`'s
    noise : standard deviation of the sensor noise on every joint, metres
    variety : how far each person's arm length and movement style differ from the generator's standard
        ones (:class:`~glu.gestures.synthetic.View`; 0: the standard people)
    max_yaw : each person turned by a random angle, a multiple of 5° in ``[−max_yaw, max_yaw]`` (degrees);
        None: facing the camera within ± 10°, as in the recordings
    body_frame : the features in the shoulder line's frame (which a turn leaves alone) instead of the torso's
    effects : whether and how the effects depend on the gesture as well as on the action
        (:class:`~glu.studies.episodes.GestureEffects`); in such a world a fraction ``failed_taps`` of an
        :class:`Ambiguity` makes the *slowest* taps fail, not random ones
    """

    name: str
    description: str = ""
    noise: float = 0.02
    variety: float = 0.0
    max_yaw: float | None = None
    body_frame: bool = False
    effects: GestureEffects = field(default_factory=GestureEffects)

    def __post_init__(self) -> None:
        if not (isinstance(self.noise, int | float) and 0 <= self.noise < 1):
            raise DataError(f"world {self.name!r}: noise={self.noise!r} must be metres in [0, 1)")
        yaw = self.max_yaw
        if yaw is not None and not (isinstance(yaw, int | float) and 0 <= yaw <= 180):
            raise DataError(f"world {self.name!r}: max_yaw={self.max_yaw!r} must be degrees in [0, 180]")
        View(variety=self.variety)  # checks the variety

    def views(self, n: int, seed: int, offset: int = 0) -> list[View]:
        """The view of each of ``n`` episodes (each person's own turn from ``(seed, VIEW_KEY, offset)``)."""
        if self.max_yaw is None:
            return [View(variety=self.variety, body_frame=self.body_frame)] * n
        k = int(self.max_yaw // 5)
        yaws = 5.0 * _rng(seed, VIEW_KEY, offset).integers(-k, k + 1, size=n)
        return [View(yaw_deg=float(y), variety=self.variety, body_frame=self.body_frame) for y in yaws]


WORLDS: dict[str, World] = _by_name(
    World(
        "easy",
        "the generator's people facing the camera, 2 cm of sensor noise; effects of the action alone",
    ),
    World(
        "hard",
        "people varied (their own arm length and movement style), 5 cm of sensor noise, each turned by "
        "up to 60° (body-frame features); the faster the gesture, the faster the object moves, whatever "
        "the action, and the slowest quarter of the taps fail",
        noise=0.05,
        variety=1.0,
        max_yaw=60.0,
        body_frame=True,
        effects=replace(GESTURE_WORLDS["gesture"], actions=AFFORDANCE_VALUES["Action"]),
    ),
)
"""The study's worlds: the generator's world, where the label noise cannot depend on the gesture, and a
harder one."""


class Episodes(NamedTuple):
    """Episodes as the world made them and as the robot perceived them.

    Attributes
    ----------
    index : array, shape (n,) — each episode's number in its seed's stream
    actions : int array, shape (n,) — the true actions (indices into the network's Action values)
    features : n arrays of shape (T_i, 3) — the repaired hand features the robot sees
    world : node → int array, shape (n,) — every node's true value (affordance nodes and words)
    perceived : node → int array, shape (n,) — the object and effect nodes as the robot perceives them
    """

    index: np.ndarray
    actions: np.ndarray
    features: list[np.ndarray]
    world: dict[str, np.ndarray]
    perceived: dict[str, np.ndarray]


def _rng(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


def draw_actions(engine: Engine, n: int, seed: int, offset: int = 0, balanced: bool = False) -> np.ndarray:
    """The actions of episodes ``offset … offset + n − 1`` (uniform; ``balanced``: cycling through them), as
    indices of the network's Action values: int array, shape (n,)."""
    k = len(engine.bn.schema.values_of("Action"))
    if balanced:
        return np.arange(n) % k
    u = _rng(seed, ACTION_KEY, offset).random(n)
    return np.minimum((u * k).astype(int), k - 1)


def draw_gestures(
    engine: Engine,
    actions: np.ndarray,
    seed: int,
    offset: int = 0,
    noise: float | None = None,
    gestures: GestureSettings | None = None,
    world: World | None = None,
) -> list[np.ndarray]:
    """The repaired hand features of each episode's gesture (the generator seeded by ``(seed, GESTURE_KEY,
    offset + i)``), arrays of shape (T_i, 3), as the robot sees them in ``world`` (default ``easy``;
    ``noise``, if given, replaces its sensor noise)."""
    names = engine.bn.schema.values_of("Action")
    gestures = gestures or GestureSettings()
    world = world or WORLDS["easy"]
    noise = world.noise if noise is None else noise
    views = world.views(len(actions), seed, offset)
    out: list[np.ndarray] = [np.empty((0, 3))] * len(actions)
    for view in dict.fromkeys(views):  # one batch per view, in the order they first appear
        rows = [i for i, v in enumerate(views) if v == view]
        batch = gesture_features(
            [names[actions[i]] for i in rows],
            [_rng(seed, GESTURE_KEY, offset + i) for i in rows],
            noise=noise,
            spike_rate=gestures.spike_rate,
            dropout_rate=gestures.dropout_rate,
            view=view,
        )
        for i, x in zip(rows, batch.features, strict=True):
            out[i] = x
    return out


def draw_world(
    engine: Engine,
    actions: np.ndarray,
    ambiguity: Ambiguity,
    seed: int,
    offset: int = 0,
    effects: Sequence[str] = EFFECTS,
    world: World | None = None,
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The object, effects and words of episodes with the given actions, and what the robot perceives.

    Returns ``(world, perceived)``: node → int array of shape (n,), every node's true value; and the
    object nodes and ``effects`` as perceived (each effect replaced by a uniformly random value with
    probability ``ambiguity.perception_noise``). In a ``world`` whose effects depend on the gesture
    (:attr:`World.effects`), the effects of objects that can move are redrawn from the speed of each
    episode's gesture (:func:`glu.studies.episodes.effects_given_gesture`, the speed read from the
    episode's own generator, :func:`glu.studies.episodes.gesture_speed`), and the taps that fail are the
    slowest ones.
    """
    n = len(actions)
    schema = engine.bn.schema
    rng = _rng(seed, WORLD_KEY, offset)
    tilt = (world or WORLDS["easy"]).effects
    if tilt.active and ambiguity.failed_taps:
        tilt = replace(tilt, failed_taps=max(tilt.failed_taps, ambiguity.failed_taps))
    fixed = {"Action": np.asarray(actions, dtype=np.intp)}
    for node in OBSERVED_OBJECT:
        p = ambiguity.objects.probabilities(node)
        fixed[node] = categorical(np.broadcast_to(p, (n, len(p))), rng)
    slow = schema.values_of("ObjVel").index("slow")
    tap = schema.values_of("Action").index("tap")
    stays = np.full(n, ambiguity.still)
    if ambiguity.failed_taps and not tilt.active:
        stays |= (fixed["Action"] == tap) & (rng.random(n) < ambiguity.failed_taps)
    drawn: dict[str, np.ndarray] = {}
    for mask in (stays, ~stays):  # the objects that stay put: ObjVel fixed slow, the rest drawn given it
        rows = np.flatnonzero(mask)
        if len(rows) == 0:
            continue
        part = {k: v[rows] for k, v in fixed.items()}
        if mask is stays:
            part["ObjVel"] = np.full(len(rows), slow, dtype=np.intp)
        for node, v in sample(engine, part, rng).items():
            drawn.setdefault(node, np.zeros(n, dtype=np.intp))[rows] = v
    if tilt.active and not ambiguity.still:
        speed = gesture_speed([_rng(seed, GESTURE_KEY, offset + i) for i in range(n)])
        drawn = effects_given_gesture(engine, drawn, speed.quantile, tilt, rng)
    noise_rng = _rng(seed, PERCEPTION_KEY, offset)
    perceived = {node: drawn[node].copy() for node in OBSERVED_OBJECT}
    for node in effects:
        k = schema.cardinality(node)
        v = drawn[node].copy()
        flip = noise_rng.random(n) < ambiguity.perception_noise
        v[flip] = noise_rng.integers(0, k, size=int(flip.sum()))
        perceived[node] = v
    return drawn, perceived


def simulate_episodes(
    engine: Engine,
    ambiguity: Ambiguity,
    n: int,
    seed: int,
    offset: int = 0,
    effects: Sequence[str] = EFFECTS,
    noise: float | None = None,
    balanced: bool = False,
    world: World | None = None,
) -> Episodes:
    """``n`` episodes of seed ``seed`` numbered from ``offset`` (:class:`Episodes`) in ``world`` (default
    ``easy``); ``noise``, if given, replaces the world's sensor noise on the joints (m); ``balanced`` cycles
    through the actions (for held-out sets)."""
    actions = draw_actions(engine, n, seed, offset, balanced)
    features = draw_gestures(engine, actions, seed, offset, noise, world=world)
    drawn, perceived = draw_world(engine, actions, ambiguity, seed, offset, effects, world)
    return Episodes(np.arange(offset, offset + n), actions, features, drawn, perceived)


def network_posteriors(
    engine: Engine,
    perceived: Mapping[str, np.ndarray],
    world: Mapping[str, np.ndarray] | None = None,
    words: bool = False,
) -> np.ndarray:
    """``p_BN(A | object, perceived effects[, words])`` of each episode, shape (n, n_actions).

    ``perceived`` holds the object and effect nodes; with ``words``, the words of ``world`` are evidence
    too. An episode whose evidence the network finds impossible (a misperceived effect it never saw with
    that object) falls back on the object alone.
    """
    evidence = dict(perceived)
    if words:
        if world is None:
            raise DataError("network_posteriors: words=True needs the episodes' world (their words)")
        evidence.update({w: world[w] for w in engine.bn.schema.word_nodes})
    p = engine.query_batch(["Action"], evidence, errors="nan")["Action"]
    bad = np.isnan(p).any(axis=1)
    if bad.any():
        obj = {k: np.asarray(perceived[k])[bad] for k in OBSERVED_OBJECT}
        p[bad] = engine.query_batch(["Action"], obj)["Action"]
    return p


def one_hot(labels: np.ndarray, k: int) -> np.ndarray:
    """Rows of ``k`` zeros with a one at each label, shape (n, k)."""
    out = np.zeros((len(labels), k))
    out[np.arange(len(labels)), labels] = 1.0
    return out


def p_hmm_reading(loglik: np.ndarray, n_frames: np.ndarray, posterior: str = "per-frame") -> np.ndarray:
    """``p_HMM(A | G)``, shape (n, A), from log-likelihoods (n, A) and frames seen ``n_frames`` (n,): equal
    priors, from the likelihoods or per frame (``exp((1/T) log L)``, the tempered reading); ``-inf`` (no
    model) gives probability 0. The formula's home is :func:`glu.gestures.calibration.p_hmm_reading`; this
    study allows the readings that need no fitted temperature (:data:`POSTERIOR_READINGS`)."""
    if posterior not in POSTERIOR_READINGS:
        raise DataError(f"unknown posterior reading {posterior!r}; allowed: {', '.join(POSTERIOR_READINGS)}")
    return calibration.p_hmm_reading(loglik, n_frames, posterior)


def label_weights(
    scheme: str,
    p_bn: np.ndarray,
    threshold: float = 0.9,
    p_hmm: np.ndarray | None = None,
    true: np.ndarray | None = None,
) -> np.ndarray:
    """Each episode's weight for each action's model, shape (n, A), by labelling ``scheme``.

    ``hard``: one for the network's arg-max; ``soft``: ``p_BN`` itself; ``confident``: the arg-max where
    ``max p_BN ≥ threshold``, no weight elsewhere; ``iterative``: the product rule ``p_HMM · p_BN``
    normalised (``p_BN`` alone without ``p_HMM``); ``true``: the true action (``true``, shape (n,)).

    >>> p_bn = np.array([[0.5, 0.3, 0.2], [0.05, 0.92, 0.03]])
    >>> label_weights("hard", p_bn).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    >>> label_weights("confident", p_bn, threshold=0.9).tolist()
    [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    >>> label_weights("iterative", p_bn, p_hmm=np.array([[0.2, 0.2, 0.6], [0.1, 0.8, 0.1]])).round(3).tolist()
    [[0.357, 0.214, 0.429], [0.007, 0.989, 0.004]]
    """
    p_bn = np.asarray(p_bn, dtype=float)
    k = p_bn.shape[1]
    if scheme == "hard":
        return one_hot(p_bn.argmax(axis=1), k)
    if scheme == "soft":
        return p_bn.copy()
    if scheme == "confident":
        return one_hot(p_bn.argmax(axis=1), k) * (p_bn.max(axis=1) >= threshold)[:, None]
    if scheme == "iterative":
        if p_hmm is None:
            return p_bn.copy()
        fused = p_hmm * p_bn
        total = fused.sum(axis=1, keepdims=True)
        return np.where(total > 0, fused / np.where(total > 0, total, 1.0), p_bn)
    if scheme == "true":
        if true is None:
            raise DataError("label_weights: the 'true' baseline needs the true actions")
        return one_hot(np.asarray(true), k)
    raise DataError(f"unknown labelling scheme {scheme!r}; allowed: {', '.join(SCHEMES + ('true',))}")


def matched_random_labels(true: np.ndarray, accuracy: float, k: int, rng: np.random.Generator) -> np.ndarray:
    """Random labels as accurate as another labeller: each episode's true action with probability
    ``accuracy``, otherwise one of the other ``k − 1`` actions uniformly; one-hot rows, shape (n, k).

    The errors depend on nothing (neither the gesture nor the action), so HMMs that learn as well from
    these as from the network's labels owe nothing to what the network knows beyond its accuracy.
    """
    check_probability(accuracy, "accuracy", "matched_random_labels")
    true = np.asarray(true, dtype=np.intp)
    right = rng.random(len(true)) < accuracy
    other = (true + rng.integers(1, k, size=len(true))) % k
    return one_hot(np.where(right, true, other), k)


def first_labels(true: np.ndarray, per_action: int, k: int) -> np.ndarray:
    """The true labels of the first ``per_action`` episodes of each action, zero rows for the rest, shape
    (n, k): the labels of the ``supervised`` learners.

    >>> first_labels(np.array([0, 1, 0, 0, 1]), 2, 2).tolist()
    [[1.0, 0.0], [0.0, 1.0], [1.0, 0.0], [0.0, 0.0], [0.0, 1.0]]
    """
    true = np.asarray(true, dtype=np.intp)
    w = one_hot(true, k)
    seen = np.cumsum(w, axis=0) * w  # the how-many-th of its action each episode is
    return w * (seen <= per_action)


def best_matching(counts: np.ndarray) -> np.ndarray:
    """The permutation ``perm`` (cluster k → action ``perm[k]``) maximising ``Σ_k counts[k, perm[k]]``
    (``counts``: cluster × action, square; brute force over every permutation, fine for a few actions)."""
    k = counts.shape[0]
    best, best_perm = -np.inf, np.arange(k)
    for perm in itertools.permutations(range(k)):
        v = counts[np.arange(k), list(perm)].sum()
        if v > best + 1e-12:
            best, best_perm = v, np.array(perm)
    return best_perm


def resampled(features: Sequence[np.ndarray], points: int = 8) -> np.ndarray:
    """Each sequence linearly resampled to ``points`` frames and flattened, shape (n, points · D): the
    fixed-length summary the unsupervised baseline clusters first."""
    out = []
    for X in features:
        t = np.linspace(0, len(X) - 1, points)
        out.append(np.stack([np.interp(t, np.arange(len(X)), X[:, d]) for d in range(X.shape[1])], 1).ravel())
    return np.array(out)
