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
* :func:`simulate_episodes` — episodes drawn as the corpus draws them
  (:mod:`glu.studies.corpus_evaluation.corpus`): the action, then the person's gesture
  (:mod:`glu.gestures.synthetic`, one seeded generator per episode, the same in every ambiguity), the object,
  the effects and the words from the network (:func:`glu.bn.sampling.sample`), and what the robot perceives of
  the effect.
* :func:`network_posteriors` — ``p_BN(A | what the robot perceived)``, one row per episode.
* :func:`label_weights` — the labelling schemes (:data:`SCHEMES`): ``hard`` (the arg-max), ``soft`` (the
  posterior as weights), ``confident`` (the arg-max, only above a threshold), ``iterative`` (the product
  rule of the robot's current HMMs and the network, relabelled until the labels stop changing); and the
  baselines' labels (:data:`BASELINES`: the ``true`` action; ``unsupervised`` clusters).
* the learners themselves: all episodes at once in :mod:`glu.studies.learning.learned_recognizers` (which also
  runs the real gestures with their labels hidden), one episode at a time in
  :mod:`glu.studies.learning.online`; the study's learning curves in
  :mod:`glu.studies.learning.study`.

Seeds: episode ``i`` of seed ``s`` has the same action and gesture in every ambiguity (the actions of a
stream numbered from ``offset`` come from ``(s, ACTION_KEY, offset)``, episode ``i``'s gesture from
``(s, GESTURE_KEY, i)``); the world (objects, effects, words) comes from ``(s, WORLD_KEY, offset)`` and the
perception noise from ``(s, PERCEPTION_KEY, offset)``. Held-out episodes use ``offset`` =
:data:`TEST_OFFSET`, never seen in training.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

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
from glu.studies.episodes import GESTURE_KEY, WORLD_KEY, GestureSettings, Scenario

SCHEMES: tuple[str, ...] = ("hard", "soft", "confident", "iterative")
"""How the robot labels an episode from its network (and, for ``iterative``, its current HMMs)."""
BASELINES: tuple[str, ...] = ("true", "unsupervised")
"""HMMs trained on the true labels (the upper bound) and on clusters matched to actions afterwards (the
lower bound). The third baseline, the network alone, recognises no gesture: its accuracy is that of its
labels."""
LEARNERS: tuple[str, ...] = SCHEMES + BASELINES
"""Every learner a study compares: the labelling schemes, then the baselines."""
POSTERIOR_READINGS: tuple[str, ...] = ("likelihood", "per-frame")
"""How ``p_HMM`` is read from the likelihoods when the robot relabels (two
of :data:`glu.gestures.calibration.READINGS`)."""
ACTION_KEY, PERCEPTION_KEY = 3, 4
"""Spawn keys of the actions and of the perception noise (the corpus uses 0 for the world, 1 for gestures)."""
TEST_OFFSET = 10_000_000
"""Held-out episodes are numbered from here (their gestures never meet a training episode's)."""
STUDY_TRAINING = TrainingConfig(n_states=6, n_mix=1, n_iter=50, tol=1e-3)
"""The study's HMMs: one Gaussian per state, short EM (as the correspondence study's)."""
OBSERVED_OBJECT: tuple[str, ...] = ("Color", "Shape", "Size")
EFFECTS: tuple[str, ...] = ("ObjVel",)
"""The effect the robot perceives by default: the object's velocity (TCDS's example)."""


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
            v = getattr(self, k)
            if not (isinstance(v, int | float) and 0 <= v <= 1):
                raise DataError(f"ambiguity {self.name!r}: {k}={v!r} must be a probability in [0, 1]")


AMBIGUITIES: dict[str, Ambiguity] = {
    a.name: a
    for a in (
        Ambiguity(
            "spheres",
            "small and medium spheres: a tap rolls them, a touch does not",
            Scenario.from_mapping({"Shape": {"sphere": 1}, "Size": {"small": 1, "medium": 1}}),
        ),
        Ambiguity("mixed", "every object, as in the robot's experiments"),
        Ambiguity("still", "objects that never move", still=True),
        Ambiguity(
            "failed_taps", "half of the taps fail: the object stays, as after a touch", failed_taps=0.5
        ),
        Ambiguity("noisy", "the effect misperceived 30 % of the time", perception_noise=0.3),
    )
}
"""The study's ambiguities, from effects that tell actions apart well to effects that mislead."""


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
    """The actions of episodes ``offset … offset + n − 1`` (uniform; ``balanced``: cycling through them)."""
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
    noise: float = 0.02,
    gestures: GestureSettings | None = None,
    view: View | None = None,
) -> list[np.ndarray]:
    """The repaired hand features of each episode's gesture (the generator seeded by ``(seed, GESTURE_KEY,
    offset + i)``), arrays of shape (T_i, 3)."""
    names = engine.bn.schema.values_of("Action")
    gestures = gestures or GestureSettings()
    rngs = [_rng(seed, GESTURE_KEY, offset + i) for i in range(len(actions))]
    batch = gesture_features(
        [names[a] for a in actions],
        rngs,
        noise=noise,
        spike_rate=gestures.spike_rate,
        dropout_rate=gestures.dropout_rate,
        view=view or View(),
    )
    return batch.features


def draw_world(
    engine: Engine,
    actions: np.ndarray,
    ambiguity: Ambiguity,
    seed: int,
    offset: int = 0,
    effects: Sequence[str] = EFFECTS,
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The object, effects and words of episodes with the given actions, and what the robot perceives.

    Returns ``(world, perceived)``: node → int array of shape (n,), every node's true value; and the
    object nodes and ``effects`` as perceived (each effect replaced by a uniformly random value with
    probability ``ambiguity.perception_noise``).
    """
    n = len(actions)
    schema = engine.bn.schema
    rng = _rng(seed, WORLD_KEY, offset)
    fixed = {"Action": np.asarray(actions, dtype=np.intp)}
    for node in OBSERVED_OBJECT:
        p = ambiguity.objects.probabilities(node)
        fixed[node] = categorical(np.broadcast_to(p, (n, len(p))), rng)
    slow = schema.values_of("ObjVel").index("slow")
    tap = schema.values_of("Action").index("tap")
    stays = np.full(n, ambiguity.still)
    if ambiguity.failed_taps:
        stays |= (fixed["Action"] == tap) & (rng.random(n) < ambiguity.failed_taps)
    world: dict[str, np.ndarray] = {}
    for mask in (stays, ~stays):  # the objects that stay put: ObjVel fixed slow, the rest drawn given it
        rows = np.flatnonzero(mask)
        if len(rows) == 0:
            continue
        part = {k: v[rows] for k, v in fixed.items()}
        if mask is stays:
            part["ObjVel"] = np.full(len(rows), slow, dtype=np.intp)
        drawn = sample(engine, part, rng)
        for node, v in drawn.items():
            world.setdefault(node, np.zeros(n, dtype=np.intp))[rows] = v
    noise_rng = _rng(seed, PERCEPTION_KEY, offset)
    perceived = {node: world[node].copy() for node in OBSERVED_OBJECT}
    for node in effects:
        k = schema.cardinality(node)
        v = world[node].copy()
        flip = noise_rng.random(n) < ambiguity.perception_noise
        v[flip] = noise_rng.integers(0, k, size=int(flip.sum()))
        perceived[node] = v
    return world, perceived


def simulate_episodes(
    engine: Engine,
    ambiguity: Ambiguity,
    n: int,
    seed: int,
    offset: int = 0,
    effects: Sequence[str] = EFFECTS,
    noise: float = 0.02,
    balanced: bool = False,
) -> Episodes:
    """``n`` episodes of seed ``seed`` numbered from ``offset`` (:class:`Episodes`); ``noise`` is the
    sensor noise on the joints (m); ``balanced`` cycles through the actions (for held-out sets)."""
    actions = draw_actions(engine, n, seed, offset, balanced)
    features = draw_gestures(engine, actions, seed, offset, noise)
    world, perceived = draw_world(engine, actions, ambiguity, seed, offset, effects)
    return Episodes(np.arange(offset, offset + n), actions, features, world, perceived)


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
    """``p_HMM(A | G)`` from log-likelihoods (n, A): equal priors, from the likelihoods or per frame
    (``exp((1/T) log L)``, the tempered reading); ``-inf`` (no model) gives probability 0. The formula's
    home is :func:`glu.gestures.calibration.p_hmm_reading`; this study allows the readings that need no
    fitted temperature (:data:`POSTERIOR_READINGS`)."""
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
