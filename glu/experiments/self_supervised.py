"""Learning gestures from what people's actions did: the robot labels what it sees with its affordance network.

TCDS 2020 (§III-B): "If the human performs an unknown action on a spherical object and obtains a high
velocity, the robot will be able to infer that the action is most probably a tap … This information can
be used to train our statistical gesture recognition system." Here the robot watches **episodes** — a
person's hand trajectory, the object, the effect and, optionally, the words someone said — without the
action's name, labels each with its Affordance–Words network, ``p_BN(Action | object, effect[, words])``,
and trains its gesture HMMs from those labels (weighted EM, :func:`glu.hmm.em.fit_weighted`).

* :class:`Ambiguity` — how well the effects tell the actions apart: the objects people act on, objects
  that never move, taps that fail (the object stays put, as after a touch), noisy perception of the effect.
  :data:`AMBIGUITIES` names the study's.
* :func:`simulate_episodes` — episodes drawn as the corpus draws them (:mod:`glu.experiments.corpus`): the
  action, then the person's gesture (:mod:`glu.gestures.synthetic`, one seeded generator per episode, the
  same in every ambiguity), the object, the effects and the words from the network
  (:func:`glu.bn.sampling.sample`), and what the robot perceives of the effect.
* :func:`network_posteriors` — ``p_BN(A | what the robot perceived)``, one row per episode.
* :func:`label_weights` — the labelling schemes (:data:`SCHEMES`): ``hard`` (the arg-max), ``soft`` (the
  posterior as weights), ``confident`` (the arg-max, only above a threshold), ``iterative`` (the product
  rule of the robot's current HMMs and the network, relabelled until the labels stop changing); and the
  baselines' labels (:data:`BASELINES`: the ``true`` action; ``unsupervised`` clusters).
* :func:`learn_recognizer` — every model trained on the whole set at once (batch); the online learner, one
  episode at a time, is :mod:`glu.experiments.online_learning`.
* :func:`real_gesture_study` — the real standing segments with their labels hidden, each paired with an
  object and an effect drawn from the network given its true action: leave-one-segment-out accuracy and the
  seated taps, for each scheme against the true labels.

Seeds: episode ``i`` of seed ``s`` has the same action and gesture in every ambiguity (the action from the
stream ``(s, ACTION_KEY)``, the gesture from ``(s, GESTURE_KEY, i)``); the world (objects, effects, words)
comes from ``(s, WORLD_KEY)`` and the perception noise from ``(s, PERCEPTION_KEY)``. Held-out episodes use
``offset`` ≥ :data:`TEST_OFFSET`, never seen in training.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.bn.inference import InferenceEngine
from glu.bn.sampling import categorical, sample
from glu.errors import DataError, ModelError
from glu.experiments.common import tidy
from glu.experiments.corpus import GESTURE_KEY, WORLD_KEY, GestureSettings, Scenario
from glu.gestures._synthetic_batch import gesture_features
from glu.gestures.corpus import LabelledSequence
from glu.gestures.invariants import Invariants
from glu.gestures.recognizer import Recognizer
from glu.gestures.synthetic import View
from glu.gestures.typicality import META_KEY, ranges_to_meta, training_range
from glu.hmm import (
    GestureHMM,
    TrainingConfig,
    kmeans_labels,
    log_softmax,
    train,
)
from glu.schema import ACTIONS

SCHEMES: tuple[str, ...] = ("hard", "soft", "confident", "iterative")
"""How the robot labels an episode from its network (and, for ``iterative``, its current HMMs)."""
BASELINES: tuple[str, ...] = ("true", "unsupervised")
"""HMMs trained on the true labels (the upper bound) and on clusters matched to actions afterwards (the
lower bound). The third baseline, the network alone, recognises no gesture: its accuracy is that of its
labels."""
LEARNERS: tuple[str, ...] = SCHEMES + BASELINES
POSTERIOR_READINGS: tuple[str, ...] = ("likelihood", "per_frame")
"""How ``p_HMM`` is read from the likelihoods when the robot relabels (:data:`glu.experiments.corpus.POSTERIORS`)."""
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
    objects : the distribution of actions and objects (:class:`~glu.experiments.corpus.Scenario`)
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


def draw_actions(
    engine: InferenceEngine, n: int, seed: int, offset: int = 0, balanced: bool = False
) -> np.ndarray:
    """The actions of episodes ``offset … offset + n − 1`` (uniform; ``balanced``: cycling through them)."""
    k = len(engine.bn.schema.values_of("Action"))
    if balanced:
        return np.arange(n) % k
    u = _rng(seed, ACTION_KEY, offset).random(n)
    return np.minimum((u * k).astype(int), k - 1)


def draw_gestures(
    engine: InferenceEngine,
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
    engine: InferenceEngine,
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
    engine: InferenceEngine,
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
    engine: InferenceEngine,
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


def p_hmm_reading(loglik: np.ndarray, n_frames: np.ndarray, posterior: str = "per_frame") -> np.ndarray:
    """``p_HMM(A | G)`` from log-likelihoods (n, A): equal priors, from the likelihoods or per frame
    (``exp((1/T) log L)``, the tempered reading); ``-inf`` (no model) gives probability 0."""
    if posterior not in POSTERIOR_READINGS:
        raise DataError(f"unknown posterior reading {posterior!r}; allowed: {', '.join(POSTERIOR_READINGS)}")
    ll = np.asarray(loglik, dtype=float)
    if posterior == "per_frame":
        ll = ll / np.asarray(n_frames, dtype=float)[:, None]
    return np.exp(log_softmax(ll))


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


# ------------------------------------------------------------------ batch learning


class Learned(NamedTuple):
    """What :func:`learn_recognizer` returns.

    Attributes
    ----------
    recognizer : the learned gesture HMMs (actions without any label weight have no model)
    weights : array, shape (n, A) — the final label weights of the training episodes
    rounds : relabelling rounds run (1 for the schemes that do not relabel)
    """

    recognizer: Recognizer
    weights: np.ndarray
    rounds: int


def _fit_all(
    features: Sequence[np.ndarray],
    W: np.ndarray,
    actions: Sequence[str],
    config: TrainingConfig,
    seed: int,
    start: Mapping[str, GestureHMM] | None = None,
) -> dict[str, GestureHMM]:
    """One model per action with enough label weight: weighted training (from ``start`` when given)."""
    lengths = np.array([len(x) for x in features])
    models = {}
    for a, name in enumerate(actions):
        w = W[:, a]
        if w @ lengths < config.n_states * config.n_mix or not np.any(w > 0):
            continue
        first = start.get(name) if start is not None else None
        models[name] = train(
            list(features), config, weights=w, seed=seed, name=name, warn=False, start=first
        ).model
    if not models:
        raise ModelError("no action has enough label weight to train its model")
    return models


def learn_recognizer(
    features: Sequence[np.ndarray],
    scheme: str,
    p_bn: np.ndarray | None = None,
    *,
    true: np.ndarray | None = None,
    actions: Sequence[str] = ACTIONS,
    config: TrainingConfig = STUDY_TRAINING,
    seed: int = 0,
    threshold: float = 0.9,
    posterior: str = "per_frame",
    max_rounds: int = 10,
    invariants: Invariants | str | None = None,
    meta: Mapping[str, Any] | None = None,
) -> Learned:
    """Train one HMM per action on unlabelled gestures, labelled by ``scheme`` (batch: all at once).

    Parameters
    ----------
    features : the training gestures' hand features, arrays of shape (T_i, 3)
    scheme : one of :data:`LEARNERS`
    p_bn : ``p_BN(A | …)`` of each gesture, shape (n, A) (every scheme but the baselines)
    true : the true action of each gesture, int array of shape (n,) (``true``; ``unsupervised`` uses it only to
        name its clusters after training, by the best matching)
    actions, config, seed : the models' names (the columns of ``p_bn``), training settings and seed
    threshold : the ``confident`` scheme's
    posterior : how ``iterative`` and ``unsupervised`` read ``p_HMM`` (:data:`POSTERIOR_READINGS`)
    max_rounds : most relabelling rounds (``iterative``, ``unsupervised``: until the arg-max labels of every
        gesture stop changing)
    invariants : the features the models are trained on (computed by the recogniser, as for any)
    """
    if scheme not in LEARNERS:
        raise DataError(f"unknown labelling scheme {scheme!r}; allowed: {', '.join(LEARNERS)}")
    spec = Invariants.parse(invariants)
    seen = [x if spec.is_raw else spec.transform(x) for x in features]
    n, k = len(seen), len(actions)
    lengths = np.array([len(x) for x in seen])
    if scheme == "unsupervised":
        W = one_hot(kmeans_labels(resampled(seen), k, seed), k)
    elif scheme == "true":
        W = label_weights("true", np.zeros((n, k)), true=true)
    else:
        if p_bn is None or np.shape(p_bn) != (n, k):
            raise DataError(f"scheme {scheme!r} needs p_bn of shape ({n}, {k})")
        W = label_weights(scheme, p_bn, threshold)
    models = _fit_all(seen, W, actions, config, seed)
    rounds = 1
    if scheme in ("iterative", "unsupervised"):
        labels = W.argmax(axis=1)
        for rounds in range(2, max_rounds + 1):  # noqa: B007 - the last value is reported
            ll = _loglik(models, actions, seen)
            p_hmm = p_hmm_reading(ll, lengths, posterior)
            W = label_weights("iterative", p_bn, p_hmm=p_hmm) if scheme == "iterative" else p_hmm
            models = _fit_all(seen, W, actions, config, seed, start=models)
            new = W.argmax(axis=1)
            if np.array_equal(new, labels):
                break
            labels = new
    if scheme == "unsupervised":
        if true is None:
            raise DataError(
                "the unsupervised baseline needs the true actions to name its clusters afterwards"
            )
        perm = best_matching(W.T @ one_hot(np.asarray(true), k))
        models = {
            actions[perm[c]]: _renamed(models[actions[c]], actions[perm[c]])
            for c in range(k)
            if actions[c] in models
        }
        W = W[:, np.argsort(perm)]
    info = {
        "scheme": scheme,
        "rounds": rounds,
        "training_gestures": n,
        **dict(config.as_dict()),
        **(meta or {}),
    }
    order = {a: models[a] for a in actions if a in models}
    return Learned(with_ranges(Recognizer(order, meta=info, features=spec), seen, W, actions), W, rounds)


def with_ranges(
    recognizer: Recognizer, seen: Sequence[np.ndarray], W: np.ndarray, actions: Sequence[str]
) -> Recognizer:
    """``recognizer`` with the typicality ranges of its models (:mod:`glu.gestures.typicality`) measured on
    the training gestures (in the recogniser's features) labelled with each action (arg-max of ``W``, shape
    (n, A)); an action without such a gesture keeps no range (the recogniser samples one when asked)."""
    labels = W.argmax(axis=1)
    ranges = {}
    for a in recognizer.actions:
        mine = [x for x, lab in zip(seen, labels, strict=True) if lab == list(actions).index(a)]
        if mine:
            ranges[a] = training_range(recognizer.models[a], mine)
    if set(ranges) == set(recognizer.actions):
        recognizer.meta[META_KEY] = ranges_to_meta(ranges)
    return recognizer


def _renamed(m: GestureHMM, name: str) -> GestureHMM:
    return GestureHMM(m.startprob, m.transmat, m.weights, m.means, m.covars, name=name)


def _loglik(
    models: Mapping[str, GestureHMM], actions: Sequence[str], seqs: Sequence[np.ndarray]
) -> np.ndarray:
    """``log L(G | a)`` of every sequence under every action's model, shape (n, A); ``-inf`` without a model."""
    have = [a for a in actions if a in models]
    ll = Recognizer({a: models[a] for a in have}).loglik_many(seqs)
    out = np.full((len(seqs), len(actions)), -np.inf)
    for j, a in enumerate(have):
        out[:, list(actions).index(a)] = ll[:, j]
    return out


def classify(recognizer: Recognizer, actions: Sequence[str], seqs: Sequence[np.ndarray]) -> np.ndarray:
    """The predicted action index (into ``actions``) of each sequence, shape (n,)."""
    ll = recognizer.loglik_many(seqs)
    names = np.array([list(actions).index(a) for a in recognizer.actions])
    return names[ll.argmax(axis=1)]


# ------------------------------------------------------------------ the real gestures


def real_gesture_study(
    engine: InferenceEngine,
    standing: Sequence[LabelledSequence],
    seated: Sequence[LabelledSequence] = (),
    *,
    learners: Sequence[str] = LEARNERS,
    ambiguity: Ambiguity = AMBIGUITIES["mixed"],
    words: bool = False,
    draws: Sequence[int] = (0, 1, 2),
    config: TrainingConfig = STUDY_TRAINING,
    invariants: Invariants | str | None = None,
    threshold: float = 0.9,
    posterior: str = "per_frame",
    data_source: str = "",
) -> pd.DataFrame:
    """The real gestures with their labels hidden: leave-one-segment-out and the seated taps, per learner.

    For each draw, every standing segment is paired with an object, an effect and words drawn from the
    network given its true action (the robot's own experience standing in for what it would have seen), and
    labelled by ``p_BN(A | object, perceived effect[, words])``. For each held-out segment, HMMs learned from
    the other segments by each learner recognise it; HMMs learned from every standing segment recognise
    the seated taps. The ``true`` learner does not depend on the draw (it is run for each, for the pairing).

    Returns
    -------
    DataFrame, one row per draw, learner and test gesture: draw, learner, test (``loso`` or ``seated``),
    recording, start, end, action, predicted (None when the learned models lack every action), correct,
    label_accuracy (the training labels' arg-max accuracy of that draw, over all standing segments).
    """
    actions = engine.bn.schema.values_of("Action")
    stand = [s for s in standing if s.action in actions]
    true = np.array([actions.index(s.action) for s in stand])
    feats = [s.xyz for s in stand]
    rows = []
    fixed: dict[str, list[tuple[str, LabelledSequence, str | None]]] = {}  # learners that ignore the draw
    for d in draws:
        world, perceived = draw_world(engine, true, ambiguity, d, 0)
        p_bn = network_posteriors(engine, perceived, world, words)
        label_acc = float((p_bn.argmax(axis=1) == true).mean())
        for learner in learners:
            if learner in fixed:
                rows += [_row(d, learner, test, s, pred, label_acc) for test, s, pred in fixed[learner]]
                continue
            common = dict(
                true=true,
                actions=actions,
                config=config,
                seed=draws[0] if learner in BASELINES else d,
                threshold=threshold,
                posterior=posterior,
                invariants=invariants,
            )
            outcome = []
            for i, held in enumerate(stand):
                rest = [j for j in range(len(stand)) if j != i]
                try:
                    rec = learn_recognizer(
                        [feats[j] for j in rest], learner, p_bn[rest], **{**common, "true": true[rest]}
                    ).recognizer
                    predicted = actions[classify(rec, actions, [held.xyz])[0]]
                except ModelError:
                    predicted = None
                outcome.append(("loso", held, predicted))
            if seated:
                rec = learn_recognizer(feats, learner, p_bn, **common).recognizer
                for s, p in zip(seated, classify(rec, actions, [s.xyz for s in seated]), strict=True):
                    outcome.append(("seated", s, actions[p]))
            if learner in BASELINES:  # true labels and clusters: the same whatever the objects and effects
                fixed[learner] = outcome
            rows += [_row(d, learner, test, s, pred, label_acc) for test, s, pred in outcome]
    return tidy(
        pd.DataFrame(rows),
        "learning_real_gestures",
        data_source,
        ambiguity=ambiguity.name,
        words=words,
        draws=list(draws),
        threshold=threshold,
        posterior=posterior,
        features=Invariants.parse(invariants).name,
        n_states=config.n_states,
        n_mix=config.n_mix,
    )


def _row(
    draw: int, learner: str, test: str, s: LabelledSequence, predicted: str | None, label_acc: float
) -> dict:
    return {
        "draw": draw,
        "learner": learner,
        "test": test,
        "recording": s.recording,
        "start": s.start,
        "end": s.end,
        "action": s.action,
        "predicted": predicted,
        "correct": predicted == s.action,
        "label_accuracy": label_acc,
    }


def real_gesture_summary(results: pd.DataFrame) -> pd.DataFrame:
    """Per learner and test: accuracy over draws and gestures, its range over draws, the labels' accuracy."""
    g = results.groupby(["learner", "test", "draw"], sort=False).agg(
        accuracy=("correct", "mean"), label_accuracy=("label_accuracy", "first"), n=("correct", "size")
    )
    out = (
        g.groupby(["learner", "test"], sort=False)
        .agg(
            accuracy=("accuracy", "mean"),
            accuracy_min=("accuracy", "min"),
            accuracy_max=("accuracy", "max"),
            label_accuracy=("label_accuracy", "mean"),
            gestures=("n", "first"),
            draws=("n", "size"),
        )
        .reset_index()
    )
    return tidy(
        out,
        "learning_real_gestures_summary",
        results.attrs.get("data_source", ""),
        **results.attrs.get("parameters", {}),
    )
