"""Every fusion strategy measured on simulated episodes: what each episode contributes to each metric.

For each episode of a chunk (:mod:`glu.studies.corpus_evaluation.corpus`) and each observed fraction ``f`` of
its gesture, the gesture HMMs of the episode's recogniser seed (a :class:`Replication`) give ``log L(G_1^t |
A)`` with ``t = ⌈f·T⌉`` (one vectorised forward pass, :class:`~glu.hmm.scoring.BatchScorer`), on the
features of the recogniser's feature set (:class:`~glu.gestures.feature_sets.FeatureSet`: the torso's or the
shoulder line's frame, and its invariances). Each :class:`Reading` names the feature set, turns the
log-likelihoods into ``p_HMM`` (as the originals, per frame, or calibrated on clean front-view gestures or on
gestures drawn like the test conditions: :data:`P_HMM_READINGS`) and infers with one network: the one the
episodes were drawn from (``generating``), or one glu learned from a simulated experiment table
(``learned``). Under each reading each strategy predicts three things:

``action``
    p(Action) once the robot has seen the object and the effect (``action_evidence``, by default Color,
    Shape, Size, ObjVel: TCDS's ``p_comb(A | X_obs, G)``). Strategies: ``gesture`` (p_HMM alone),
    ``network`` (p_BN(A | X_obs) alone), ``hard``, ``virtual``, ``jeffrey``, ``product``
    (:func:`glu.fusion.fuse_action_tables`). For the action itself virtual evidence *is* the product rule,
    and Jeffrey's rule returns p_HMM restricted to the actions the evidence allows (tested properties).
``effect``
    p(ObjVel) before the effect, from the object (``effect_evidence``: Color, Shape, Size) and the
    gesture — effect anticipation. Strategies ``network``, ``hard``, ``virtual``, ``jeffrey``
    (:func:`glu.fusion.fuse_tables`), and the reference ``true_action`` (the true action as hard
    evidence: the best any recogniser could do).
``words``
    the words a person uses to describe the scene: p(word present) for every word of the vocabulary, given
    the object and the effect (``words_evidence``) and the gesture, scored against the words the episode's
    person said (each word present or absent). Strategies as for the effect. (The grammar's best sentence
    was checked here before; its object and effect words were right in every episode, since both are
    observed, and its verb says no more than the action's accuracy: it told the strategies apart by nothing
    the action does not.)

The network alone and the true action (an oracle: the best any recogniser could do) stand beside the
fusion rules for the effect and the words; for the action the oracle is right by definition.
Each prediction contributes per-episode statistics — for the action and the effect correct (top choice
right), log-loss ``−ln max(p_true, LOG_FLOOR)``, Brier ``Σ_k (p_k − y_k)²``, and at the full gesture the
top-label calibration bins (count, confidence, correct); for the words the mean over the vocabulary of the
Bernoulli log-loss ``−ln max(p or 1 − p of what was said, LOG_FLOOR)`` and of the Brier score ``(p − y)²``
— which :mod:`glu.studies.corpus_evaluation.intervals` sums with two-level bootstrap weights (seeds, then
episodes). Each network is queried once per distinct evidence (:func:`network_tables`), never per episode.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from glu.bn.inference import Engine
from glu.errors import DataError, ModelError
from glu.fusion import STRATEGIES, fuse_action_tables, fuse_tables
from glu.gestures.calibration import READINGS, Calibration, p_hmm_reading
from glu.gestures.feature_sets import FEATURE_SET_NAMES, FeatureSet
from glu.gestures.synthetic import View
from glu.hmm import BatchScorer
from glu.schema import ACTIONS, AFFORDANCE_NODES
from glu.stats import accumulate, poisson_weights, seed_counts
from glu.studies.corpus_evaluation.corpus import Chunk, simulate_chunk
from glu.studies.corpus_evaluation.intervals import BOOT_KEY, SEEDS_KEY
from glu.studies.corpus_evaluation.network_tables import EFFECT, NetworkTables, network_tables
from glu.studies.episodes import VIEWPOINTS, Condition, GestureSettings, Scenario

TARGETS: tuple[str, ...] = ("action", "effect", "words")
EVAL_STRATEGIES: tuple[str, ...] = ("gesture", "network", *STRATEGIES, "true_action")
"""Every strategy measured: the gesture HMMs alone, the network alone, the fusion rules of
:mod:`glu.fusion`, and the reference ``true_action``."""
APPLICABLE: dict[str, tuple[str, ...]] = {
    "action": ("gesture", "network", *STRATEGIES),
    "effect": ("network", "hard", "virtual", "jeffrey", "true_action"),
    "words": ("network", "hard", "virtual", "jeffrey", "true_action"),
}
"""The strategies that predict each target (p_HMM alone says nothing about effects; the product rule
infers only the action, and for effects it equals virtual evidence)."""
GESTURE_FREE: tuple[str, ...] = ("network", "true_action")
"""Strategies that ignore the gesture (their predictions are the same at every fraction)."""
LOG_FLOOR = 1e-6
"""Log-loss floors probabilities at this (a hard decision's log-loss is then 13.8 × its error rate)."""
PREDICTION_STATS: tuple[str, ...] = ("correct", "log_loss", "brier")
WORD_STATS: tuple[str, ...] = ("log_loss", "brier")
"""The words' statistics: means over the vocabulary of each word's Bernoulli log-loss and Brier score."""
P_HMM_READINGS: dict[str, str] = {
    **READINGS,
    "calibrated-matched": "as calibrated, β fitted on held-out gestures drawn like the test conditions (the "
    "sweep's viewpoints and noise levels)",
}
"""How p_HMM is read: the library's readings (:data:`glu.gestures.calibration.READINGS`; ``calibrated``
is fitted on clean front-view gestures, the training distribution), and ``calibrated-matched``."""
CALIBRATED: tuple[str, ...] = ("calibrated", "calibrated-matched")


@dataclass(frozen=True)
class EvaluationSettings:
    """What is measured (the defaults are glu's, used by ``glu evaluate`` and the notebook).

    Attributes
    ----------
    fractions : observed fractions of the gesture, each in (0, 1]
    strategies : a subset of :data:`EVAL_STRATEGIES`
    action_evidence, effect_evidence, words_evidence : the observed affordance nodes when the robot
        names the action, anticipates the effect, predicts the words (never Action)
    bins : calibration bins of the effect's top-label confidence (equal widths on [0, 1])
    bootstrap : bootstrap replicates (Poisson weights)
    log_floor : see :data:`LOG_FLOOR`
    """

    fractions: tuple[float, ...] = (0.2, 0.4, 0.6, 0.8, 1.0)
    strategies: tuple[str, ...] = EVAL_STRATEGIES
    action_evidence: tuple[str, ...] = ("Color", "Shape", "Size", "ObjVel")
    effect_evidence: tuple[str, ...] = ("Color", "Shape", "Size")
    words_evidence: tuple[str, ...] = ("Color", "Shape", "Size", "ObjVel")
    bins: int = 10
    bootstrap: int = 1000
    log_floor: float = LOG_FLOOR

    def __post_init__(self) -> None:
        if not self.fractions or any(not (isinstance(f, int | float) and 0 < f <= 1) for f in self.fractions):
            raise DataError(f"fractions {list(self.fractions)}: each must be a number in (0, 1]")
        if len(set(self.fractions)) != len(self.fractions):
            raise DataError(f"fractions {list(self.fractions)}: each may appear once")
        bad = [s for s in self.strategies if s not in EVAL_STRATEGIES]
        if bad or not self.strategies:
            raise DataError(
                f"unknown strategy {bad[0] if bad else '(none)'!r}; allowed: {', '.join(EVAL_STRATEGIES)}"
            )
        for name in ("action_evidence", "effect_evidence", "words_evidence"):
            nodes = getattr(self, name)
            wrong = [n for n in nodes if n not in AFFORDANCE_NODES or n == "Action"]
            if wrong:
                allowed = ", ".join(n for n in AFFORDANCE_NODES if n != "Action")
                raise DataError(f"{name}: {wrong[0]!r} cannot be observed here; allowed: {allowed}")
            if EFFECT in nodes and name == "effect_evidence":
                raise DataError("effect_evidence: the effect (ObjVel) is what is predicted; leave it out")
        if not (isinstance(self.bins, int) and 1 <= self.bins <= 100):
            raise DataError(f"bins={self.bins!r}: a whole number from 1 to 100")
        if not (isinstance(self.bootstrap, int) and 0 <= self.bootstrap <= 10_000):
            raise DataError(f"bootstrap={self.bootstrap!r}: a whole number of replicates from 0 to 10000")
        if not (isinstance(self.log_floor, float) and 0 < self.log_floor < 1):
            raise DataError(f"log_floor={self.log_floor!r}: a number in (0, 1)")

    @property
    def full_index(self) -> int:
        """The index of the largest observed fraction (where the calibration bins are kept)."""
        return int(np.argmax(self.fractions))

    def strategies_for(self, target: str) -> tuple[str, ...]:
        """The chosen strategies that predict ``target``, in :data:`EVAL_STRATEGIES` order."""
        return tuple(s for s in EVAL_STRATEGIES if s in self.strategies and s in APPLICABLE[target])


def statistic_columns(settings: EvaluationSettings) -> pd.DataFrame:
    """The per-episode statistics a chunk sums, one row per column of its statistics matrix.

    Columns: target, strategy, fraction, stat (``correct``, ``log_loss``, ``brier``; ``bin_n``,
    ``bin_confidence``, ``bin_correct`` with ``bin`` ≥ 0 for the action and the effect, at the largest
    observed fraction only; :data:`WORD_STATS` for the words), bin (−1 if none). Row 0 is the episode count
    (target ``episodes``).
    """
    full = max(settings.fractions)
    rows: list[tuple[str, str, float, str, int]] = [("episodes", "", math.nan, "n", -1)]
    for target in TARGETS:
        for s in settings.strategies_for(target):
            for f in settings.fractions:
                if target == "words":
                    rows += [(target, s, f, st, -1) for st in WORD_STATS]
                    continue
                rows += [(target, s, f, st, -1) for st in PREDICTION_STATS]
                if f == full:
                    rows += [
                        (target, s, f, st, b)
                        for b in range(settings.bins)
                        for st in ("bin_n", "bin_confidence", "bin_correct")
                    ]
    return pd.DataFrame(rows, columns=["target", "strategy", "fraction", "stat", "bin"])


@dataclass(frozen=True)
class Reading:
    """How the robot reads one episode: the network it infers with, and how it reads p_HMM.

    Attributes
    ----------
    inference_network : ``"generating"`` (the network the episodes are drawn from) or ``"learned"`` (learned
        by glu from an independent simulated experiment table, :data:`INFERENCE_NETWORKS`)
    learn_experiments : rows of that table (0 for the generating network)
    p_hmm : a name of :data:`P_HMM_READINGS`
    features : the recogniser's feature set (:data:`glu.gestures.feature_sets.FEATURE_SET_NAMES`)
    """

    inference_network: str = "generating"
    learn_experiments: int = 0
    p_hmm: str = "likelihood"
    features: str = "raw"

    def __post_init__(self) -> None:
        if self.inference_network not in INFERENCE_NETWORKS:
            raise DataError(
                f"unknown inference network {self.inference_network!r}; allowed: "
                f"{', '.join(INFERENCE_NETWORKS)}"
            )
        if self.p_hmm not in P_HMM_READINGS:
            raise DataError(f"unknown reading of p_HMM {self.p_hmm!r}; allowed: {', '.join(P_HMM_READINGS)}")
        if self.features not in FEATURE_SET_NAMES:
            raise DataError(f"unknown feature set {self.features!r}; allowed: {', '.join(FEATURE_SET_NAMES)}")
        learned = self.inference_network == "learned"
        if learned != (self.learn_experiments > 0):
            raise DataError("learn_experiments: a positive number of rows for a learned network, 0 otherwise")

    @property
    def network(self) -> str:
        """The network's label: ``generating`` or ``learned-N``."""
        return "generating" if self.inference_network == "generating" else f"learned-{self.learn_experiments}"


INFERENCE_NETWORKS: dict[str, str] = {
    "generating": "the network the episodes are drawn from (a correct model of the world)",
    "learned": "learned by K2 + BIC from learn_experiments rows drawn from that network (limited experience)",
}
"""The networks an episode may be read with: name → what it is."""


@dataclass(frozen=True, eq=False)
class Replication:
    """One recogniser seed's robot: its recognisers (one per feature set), the calibrations of their p_HMM,
    the networks it infers with.

    Attributes
    ----------
    scorers : feature set → the gesture recogniser as a :class:`~glu.hmm.scoring.BatchScorer` (models
        in the order of :data:`glu.schema.ACTIONS`), trained on that feature set
    calibrations : feature set → calibrated reading (``calibrated``, ``calibrated-matched``) → its β per
        observed fraction (a reading the sweep does not use may be left out)
    tables : network label (:attr:`Reading.network`) → target → :class:`NetworkTables`
    """

    scorers: Mapping[str, BatchScorer]
    calibrations: Mapping[str, Mapping[str, Calibration]]
    tables: Mapping[str, Mapping[str, NetworkTables]]

    def __post_init__(self) -> None:
        for features, scorer in self.scorers.items():
            names = tuple(m.name for m in scorer.models)
            if names != ACTIONS:
                raise ModelError(
                    f"the {features} recogniser's models must be {', '.join(ACTIONS)} in this order, "
                    f"not {names}"
                )


def target_tables(engine: Engine, settings: EvaluationSettings) -> dict[str, NetworkTables]:
    """The :class:`NetworkTables` of each target for one network (queried once per network)."""
    return {
        "action": network_tables(engine, settings.action_evidence, EFFECT),
        "effect": network_tables(engine, settings.effect_evidence, EFFECT),
        "words": network_tables(engine, settings.words_evidence, "words"),
    }


@dataclass(frozen=True, eq=False)
class Evaluator:
    """Everything needed to simulate and score chunks of episodes; built once, sent to every worker.

    Attributes
    ----------
    world : the Affordance–Words network the episodes are drawn from
    replications : one :class:`Replication` per recogniser seed; each has its own episodes
    readings : how each episode is read (network × p_HMM); every chunk is scored under each
    settings : what is measured
    seed, chunk_size : the corpus's seed and chunk size
    scenario, gestures, views : the corpus's settings
        (:func:`~glu.studies.corpus_evaluation.corpus.simulate_chunk`)
    """

    world: Engine
    replications: tuple[Replication, ...]
    readings: tuple[Reading, ...] = (Reading(),)
    settings: EvaluationSettings = EvaluationSettings()
    seed: int = 0
    chunk_size: int = 2000
    scenario: Scenario = Scenario()
    gestures: GestureSettings = GestureSettings()
    views: Mapping[str, View] = field(default_factory=lambda: dict(VIEWPOINTS))
    columns: pd.DataFrame = field(init=False, repr=False)
    counts: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.replications:
            raise DataError("an evaluation needs at least one recogniser (replication)")
        if not self.readings or len(set(self.readings)) != len(self.readings):
            raise DataError(
                "an evaluation needs distinct readings (network × p_HMM × features), at least one"
            )
        for r in self.readings:
            missing = [k for k, rep in enumerate(self.replications) if r.network not in rep.tables]
            if missing:
                raise DataError(f"replication {missing[0]} has no {r.network} network")
            if any(r.features not in rep.scorers for rep in self.replications):
                raise DataError(f"every replication needs a recogniser of the feature set {r.features!r}")
            if r.p_hmm in CALIBRATED and any(
                r.p_hmm not in rep.calibrations.get(r.features, {}) for rep in self.replications
            ):
                raise DataError(f"the {r.p_hmm} reading of p_HMM needs every replication's calibration")
        object.__setattr__(self, "columns", statistic_columns(self.settings))
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(SEEDS_KEY,)))
        object.__setattr__(self, "counts", seed_counts(len(self.replications), self.settings.bootstrap, rng))

    @property
    def feature_sets(self) -> tuple[str, ...]:
        """The feature sets the readings use, in their order."""
        return tuple(dict.fromkeys(r.features for r in self.readings))

    def simulate(self, condition: Condition, chunk: int, n: int, replication: int = 0) -> Chunk:
        """The episodes of one chunk of one replication
        (:func:`~glu.studies.corpus_evaluation.corpus.simulate_chunk`; in the shoulder line's frame too when
        a feature set needs it)."""
        return simulate_chunk(
            self.world,
            condition,
            self.seed,
            chunk,
            n,
            self.chunk_size,
            self.scenario,
            self.gestures,
            self.views,
            replication,
            body=any(FeatureSet.parse(f).body for f in self.feature_sets),
        )

    def weights(self, replication: int, chunk: int, n: int) -> np.ndarray:
        """The two-level bootstrap weights of a chunk's episodes, shape (n, B + 1)
        (:func:`~glu.stats.poisson_weights` with this replication's seed
        counts)."""
        key = (BOOT_KEY, replication, chunk)
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=key))
        return poisson_weights(n, self.settings.bootstrap, rng, self.counts[:, replication])

    def run_chunk(self, condition: Condition, replication: int, chunk: int, n: int) -> np.ndarray:
        """Simulate and score one chunk of one replication under every reading: shape (R, B + 1, K).

        ``[r, 0]`` holds the plain sums of reading r (every weight 1), ``[r, 1:]`` the bootstrap
        replicates; column k is ``self.columns`` row k. The weights depend on (seed, replication, chunk)
        only, so every reading and strategy is resampled on the same episodes (paired).
        """
        episodes = self.simulate(condition, chunk, n, replication)
        weights = self.weights(replication, chunk, n)
        blocks = [b for reading in self.episode_statistics(episodes, replication) for b in reading]
        sums = accumulate([np.concatenate(blocks, axis=1)], weights)  # one product for every reading
        return sums.reshape(len(sums), len(self.readings), -1).transpose(1, 0, 2)

    def seen(self, episodes: Chunk, features: str) -> list[np.ndarray]:
        """What the recogniser of a feature set sees of each episode's gesture: the hand in its frame, with
        its invariances (computed online, so a prefix of the result is the result of the prefix): one array
        per episode, shape (T_i, 3), in feature units."""
        spec = FeatureSet.parse(features)
        xs = episodes.body_features if spec.body else episodes.features
        if xs is None:
            raise DataError(f"the feature set {features!r} needs the episodes in the shoulder line's frame")
        return xs if spec.invariants.is_raw else [spec.invariants.transform(x) for x in xs]

    def loglik(
        self, features: Sequence[np.ndarray], replication: int = 0, feature_set: str = "raw"
    ) -> tuple[np.ndarray, np.ndarray]:
        """``log L(G_1^t | A)`` at every observed fraction, shape (n, F, K), and t, shape (n, F), of
        sequences already in the feature set's features (:meth:`seen`)."""
        lengths = np.array([len(x) for x in features])
        f = np.asarray(self.settings.fractions)
        ends = np.maximum(np.ceil(np.round(f[None, :] * lengths[:, None], 9)).astype(int), 1)
        return self.replications[replication].scorers[feature_set].loglik_at(features, ends), ends

    def p_hmm(
        self,
        features: Sequence[np.ndarray],
        reading: str = "likelihood",
        replication: int = 0,
        feature_set: str = "raw",
    ) -> np.ndarray:
        """``p_HMM(A | G_1^t)`` at every observed fraction, shape (n, F, K)."""
        loglik, ends = self.loglik(features, replication, feature_set)
        return self._read(loglik, ends, reading, replication, feature_set)

    def _read(
        self, loglik: np.ndarray, ends: np.ndarray, reading: str, replication: int, feature_set: str
    ) -> np.ndarray:
        beta = None
        if reading in CALIBRATED:
            cal = self.replications[replication].calibrations[feature_set][reading]
            beta = np.broadcast_to(
                np.array([cal.at(f) for f in self.settings.fractions])[None, :], ends.shape
            )
        return p_hmm_reading(loglik, ends, "calibrated" if reading in CALIBRATED else reading, beta)

    def episode_statistics(self, episodes: Chunk, replication: int = 0) -> list[list[np.ndarray]]:
        """Per-episode statistics for each reading: blocks of columns in the order of ``self.columns``
        (each shape (n, k)), one list of blocks per reading of ``self.readings``. Each feature set's
        forward pass is shared by the readings that use it."""
        rep = self.replications[replication]
        scored = {f: self.loglik(self.seen(episodes, f), replication, f) for f in self.feature_sets}
        cache: dict[tuple, np.ndarray] = {}  # blocks the readings of one network share
        out = []
        for i, r in enumerate(self.readings):
            loglik, ends = scored[r.features]
            q = self._read(loglik, ends, r.p_hmm, replication, r.features)
            out.append(self._statistics(episodes, q, rep.tables[r.network], r.network, i, cache))
        return out

    def _statistics(
        self,
        episodes: Chunk,
        q: np.ndarray,
        tables: Mapping[str, NetworkTables],
        network: str,
        reading: int,
        cache: dict[tuple, np.ndarray],
    ) -> list[np.ndarray]:
        """The blocks of one reading. Keys are shared by the readings of one network for the gesture-free
        strategies and for the hard decision, which depends on p_HMM only through its top action (the same
        under every reading of one feature set unless a calibrated one is flat); the others carry the
        reading's index."""
        s, codes = self.settings, episodes.codes
        shape = {n: self.world.bn.schema.cardinality(n) for n in AFFORDANCE_NODES}
        action = codes["Action"]
        top = np.argmax(q, axis=-1).tobytes()

        def key(target: str, strat: str) -> tuple:
            shared = strat in GESTURE_FREE or strat == "hard"
            return (network, target, strat, top if strat == "hard" else b"", -1 if shared else reading)

        blocks = [np.ones((q.shape[0], 1))]
        t = tables["action"]
        p_a = t.p_action[t.combo(codes, [shape[x] for x in t.nodes])]  # (n, K)
        for strat in s.strategies_for("action"):
            if key("action", strat) not in cache:
                if strat == "gesture":
                    p = q
                elif strat == "network":
                    p = np.broadcast_to(p_a[:, None, :], q.shape)
                else:
                    p = fuse_action_tables(p_a[:, None, :], q, strat)
                cache[key("action", strat)] = _prediction_stats(p, action, s, s.bins)
            blocks.append(cache[key("action", strat)])
        said = np.stack([codes[w] == 1 for w in self.world.binary_leaves], axis=1)  # (n, W)
        for target in ("effect", "words"):
            t = tables[target]
            c = t.combo(codes, [shape[x] for x in t.nodes])
            # (n, K), and (n, K, V) for the effect, (n, K, W) for the words: p(word present | a)
            p_a, p_x = t.p_action[c], t.p_given_action[c]
            for strat in s.strategies_for(target):
                if key(target, strat) not in cache:
                    p = self._fused(strat, p_a, p_x, q, action)
                    cache[key(target, strat)] = (
                        _prediction_stats(p, codes[EFFECT], s, s.bins)
                        if target == "effect"
                        else _word_stats(p, said, s.log_floor)
                    )
                blocks.append(cache[key(target, strat)])
        return blocks

    def _fused(
        self, strat: str, p_a: np.ndarray, p_x: np.ndarray, q: np.ndarray, action: np.ndarray
    ) -> np.ndarray:
        """p(X) per episode and fraction, shape (n, F, V), for a target other than Action (for the words,
        each word's probability of being said: every rule mixes the actions' answers linearly)."""
        n, F, _ = q.shape
        if strat == "network":
            p = np.einsum("nk,nkv->nv", p_a, p_x)
        elif strat == "true_action":
            p = p_x[np.arange(n), action]
        else:
            return _uniform_if_undefined(fuse_tables(p_x[:, None], p_a[:, None], q, strat))
        return np.broadcast_to(p[:, None, :], (n, F, p.shape[-1]))


def _word_stats(p: np.ndarray, said: np.ndarray, floor: float) -> np.ndarray:
    """The words' mean Bernoulli log-loss and Brier score per episode and fraction, shape (n, F · 2), in the
    order of :func:`statistic_columns`; ``p`` (n, F, W) the probability that each word is said, ``said``
    (n, W) whether it was."""
    y = said[:, None, :].astype(float)
    p = np.where(np.isfinite(p), p, 0.5)
    p_true = np.where(y > 0, p, 1.0 - p)
    log_loss = -np.log(np.maximum(p_true, floor)).mean(axis=-1)
    brier = ((p - y) ** 2).mean(axis=-1)
    return np.stack([log_loss, brier], axis=-1).reshape(len(p), -1)


def _uniform_if_undefined(p: np.ndarray) -> np.ndarray:
    bad = ~np.isfinite(p).all(axis=-1)
    if bad.any():
        p = p.copy()
        p[bad] = 1.0 / p.shape[-1]
    return p


def _prediction_stats(p: np.ndarray, truth: np.ndarray, s: EvaluationSettings, bins: int) -> np.ndarray:
    """correct, log-loss, Brier per episode and fraction (and calibration bins at the full fraction),
    shape (n, F · 3 + 3 · bins), in the order of :func:`statistic_columns`."""
    n, F, V = p.shape
    p = _uniform_if_undefined(p)
    y = np.broadcast_to(truth[:, None], (n, F))
    p_true = np.take_along_axis(p, y[..., None], axis=-1)[..., 0]
    top = np.argmax(p, axis=-1)
    correct = (top == y).astype(float)
    log_loss = -np.log(np.maximum(p_true, s.log_floor))
    brier = (p**2).sum(axis=-1) - 2 * p_true + 1.0
    stats = np.stack([correct, log_loss, brier], axis=-1)  # (n, F, 3)
    j = s.full_index
    conf = np.take_along_axis(p[:, j], top[:, j, None], axis=-1)[:, 0]
    b = np.minimum((conf * bins).astype(int), bins - 1)
    onehot = b[:, None] == np.arange(bins)  # (n, bins)
    per_bin = np.stack([onehot, onehot * conf[:, None], onehot * correct[:, j, None]], axis=-1)
    return np.concatenate(
        [
            stats[:, : j + 1].reshape(n, -1),
            per_bin.reshape(n, -1).astype(float),
            stats[:, j + 1 :].reshape(n, -1),
        ],
        axis=1,
    )
