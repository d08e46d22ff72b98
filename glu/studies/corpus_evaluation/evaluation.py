"""Every fusion strategy measured on simulated episodes: what each episode contributes to each metric.

For each episode of a chunk (:mod:`glu.studies.corpus_evaluation.corpus`) and each observed fraction ``f`` of
its gesture, the gesture HMMs of the episode's recogniser seed (a :class:`Replication`) give ``log L(G_1^t |
A)`` with ``t = ⌈f·T⌉`` (one vectorised forward pass, :class:`~glu.hmm.scoring.BatchScorer`). Each
:class:`Reading` turns them into ``p_HMM`` (as the originals, per frame, or calibrated:
:mod:`glu.gestures.calibration`) and infers with one network: the one the episodes were drawn from
(``generating``), or one glu learned from a simulated experiment table (``learned``). Under each reading each
strategy predicts three things:

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
``description``
    the best sentence of the grammar under the fused word probabilities (``description_evidence``: the
    object and the effect; :func:`glu.language.batch.best_sentences`), checked against the episode: does
    its verb name the action, its object words the object, its effect phrase the motion
    (:func:`glu.language.batch.agreement`)? Strategies as for the effect.

The network alone and the true action (an oracle: the best any recogniser could do) stand beside the
fusion rules for the effect and the description; for the action the oracle is right by definition.
Each prediction contributes per-episode statistics — correct (top choice right), log-loss
``−ln max(p_true, LOG_FLOOR)``, Brier ``Σ_k (p_k − y_k)²``, and at the full gesture the top-label
calibration bins (count, confidence, correct) of the action and the effect — which
:mod:`glu.studies.corpus_evaluation.intervals` sums with two-level bootstrap weights (seeds, then episodes).
Each network is queried once per distinct evidence (:func:`network_tables`), never per episode.
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
from glu.gestures.synthetic import View
from glu.hmm import BatchScorer
from glu.language.batch import ASPECTS, agreement, best_sentences
from glu.schema import ACTIONS, AFFORDANCE_NODES
from glu.stats import accumulate, poisson_weights, seed_counts
from glu.studies.corpus_evaluation.corpus import Chunk, simulate_chunk
from glu.studies.corpus_evaluation.intervals import BOOT_KEY, SEEDS_KEY
from glu.studies.corpus_evaluation.network_tables import EFFECT, NetworkTables, network_tables
from glu.studies.episodes import VIEWPOINTS, Condition, GestureSettings, Scenario

TARGETS: tuple[str, ...] = ("action", "effect", "description")
EVAL_STRATEGIES: tuple[str, ...] = ("gesture", "network", *STRATEGIES, "true_action")
"""Every strategy measured: the gesture HMMs alone, the network alone, the fusion rules of
:mod:`glu.fusion`, and the reference ``true_action``."""
APPLICABLE: dict[str, tuple[str, ...]] = {
    "action": ("gesture", "network", *STRATEGIES),
    "effect": ("network", "hard", "virtual", "jeffrey", "true_action"),
    "description": ("network", "hard", "virtual", "jeffrey", "true_action"),
}
"""The strategies that predict each target (p_HMM alone says nothing about effects; the product rule
infers only the action, and for effects it equals virtual evidence)."""
GESTURE_FREE: tuple[str, ...] = ("network", "true_action")
"""Strategies that ignore the gesture (their predictions are the same at every fraction)."""
DESCRIBED: tuple[str, ...] = ("Action", "Color", "Shape", "Size", "ObjVel")
"""The nodes a description is checked against."""
LOG_FLOOR = 1e-6
"""Log-loss floors probabilities at this (a hard decision's log-loss is then 13.8 × its error rate)."""
PREDICTION_STATS: tuple[str, ...] = ("correct", "log_loss", "brier")


@dataclass(frozen=True)
class EvaluationSettings:
    """What is measured (the defaults are glu's, used by ``glu evaluate`` and the notebook).

    Attributes
    ----------
    fractions : observed fractions of the gesture, each in (0, 1]
    strategies : a subset of :data:`EVAL_STRATEGIES`
    action_evidence, effect_evidence, description_evidence : the observed affordance nodes when the
        robot names the action, anticipates the effect, describes the scene (never Action)
    bins : calibration bins of the effect's top-label confidence (equal widths on [0, 1])
    bootstrap : bootstrap replicates (Poisson weights)
    log_floor : see :data:`LOG_FLOOR`
    """

    fractions: tuple[float, ...] = (0.2, 0.4, 0.6, 0.8, 1.0)
    strategies: tuple[str, ...] = EVAL_STRATEGIES
    action_evidence: tuple[str, ...] = ("Color", "Shape", "Size", "ObjVel")
    effect_evidence: tuple[str, ...] = ("Color", "Shape", "Size")
    description_evidence: tuple[str, ...] = ("Color", "Shape", "Size", "ObjVel")
    bins: int = 10
    bootstrap: int = 200
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
        for name in ("action_evidence", "effect_evidence", "description_evidence"):
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
    observed fraction only; the aspects of :data:`glu.language.batch.ASPECTS` and ``all`` for
    descriptions), bin (−1 if none). Row 0 is the episode count (target ``episodes``).
    """
    full = max(settings.fractions)
    rows: list[tuple[str, str, float, str, int]] = [("episodes", "", math.nan, "n", -1)]
    for target in TARGETS:
        for s in settings.strategies_for(target):
            for f in settings.fractions:
                if target == "description":
                    rows += [(target, s, f, a, -1) for a in (*ASPECTS, "all")]
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
    p_hmm : a name of :data:`glu.gestures.calibration.READINGS`
    """

    inference_network: str = "generating"
    learn_experiments: int = 0
    p_hmm: str = "likelihood"

    def __post_init__(self) -> None:
        if self.inference_network not in INFERENCE_NETWORKS:
            raise DataError(
                f"unknown inference network {self.inference_network!r}; allowed: "
                f"{', '.join(INFERENCE_NETWORKS)}"
            )
        if self.p_hmm not in READINGS:
            raise DataError(f"unknown reading of p_HMM {self.p_hmm!r}; allowed: {', '.join(READINGS)}")
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
    """One recogniser seed's robot: its recogniser, the calibration of its p_HMM, the networks it infers with.

    Attributes
    ----------
    scorer : the gesture recogniser as a :class:`~glu.hmm.scoring.BatchScorer` (models in the order of
        :data:`glu.schema.ACTIONS`)
    calibration : the calibrated reading's β per observed fraction (None: no ``calibrated`` reading)
    tables : network label (:attr:`Reading.network`) → target → :class:`NetworkTables`
    """

    scorer: BatchScorer
    calibration: Calibration | None
    tables: Mapping[str, Mapping[str, NetworkTables]]

    def __post_init__(self) -> None:
        names = tuple(m.name for m in self.scorer.models)
        if names != ACTIONS:
            raise ModelError(
                f"the recogniser's models must be {', '.join(ACTIONS)} in this order, not {names}"
            )


def target_tables(engine: Engine, settings: EvaluationSettings) -> dict[str, NetworkTables]:
    """The :class:`NetworkTables` of each target for one network (queried once per network)."""
    return {
        "action": network_tables(engine, settings.action_evidence, EFFECT),
        "effect": network_tables(engine, settings.effect_evidence, EFFECT),
        "description": network_tables(engine, settings.description_evidence, "words"),
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
            raise DataError("an evaluation needs distinct readings (network × p_HMM), at least one")
        for r in self.readings:
            missing = [k for k, rep in enumerate(self.replications) if r.network not in rep.tables]
            if missing:
                raise DataError(f"replication {missing[0]} has no {r.network} network")
            if r.p_hmm == "calibrated" and any(rep.calibration is None for rep in self.replications):
                raise DataError("the calibrated reading of p_HMM needs every replication's calibration")
        object.__setattr__(self, "columns", statistic_columns(self.settings))
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(SEEDS_KEY,)))
        object.__setattr__(self, "counts", seed_counts(len(self.replications), self.settings.bootstrap, rng))

    def simulate(self, condition: Condition, chunk: int, n: int, replication: int = 0) -> Chunk:
        """The episodes of one chunk of one replication
        (:func:`~glu.studies.corpus_evaluation.corpus.simulate_chunk`)."""
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

    def loglik(self, features: Sequence[np.ndarray], replication: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """``log L(G_1^t | A)`` at every observed fraction, shape (n, F, K), and t, shape (n, F)."""
        lengths = np.array([len(x) for x in features])
        f = np.asarray(self.settings.fractions)
        ends = np.maximum(np.ceil(np.round(f[None, :] * lengths[:, None], 9)).astype(int), 1)
        return self.replications[replication].scorer.loglik_at(features, ends), ends

    def p_hmm(
        self, features: Sequence[np.ndarray], reading: str = "likelihood", replication: int = 0
    ) -> np.ndarray:
        """``p_HMM(A | G_1^t)`` at every observed fraction, shape (n, F, K)."""
        loglik, ends = self.loglik(features, replication)
        return self._read(loglik, ends, reading, replication)

    def _read(self, loglik: np.ndarray, ends: np.ndarray, reading: str, replication: int) -> np.ndarray:
        cal = self.replications[replication].calibration
        beta = None
        if reading == "calibrated":
            beta = np.broadcast_to(
                np.array([cal.at(f) for f in self.settings.fractions])[None, :], ends.shape
            )
        return p_hmm_reading(loglik, ends, reading, beta)

    def episode_statistics(self, episodes: Chunk, replication: int = 0) -> list[list[np.ndarray]]:
        """Per-episode statistics for each reading: blocks of columns in the order of ``self.columns``
        (each shape (n, k)), one list of blocks per reading of ``self.readings``.

        Every description of the chunk (all readings, strategies and fractions) is found in one call of
        :func:`~glu.language.batch.best_sentences`, whose cost is mostly per call, not per row.
        """
        loglik, ends = self.loglik(episodes.features, replication)
        rep = self.replications[replication]
        cache: dict[tuple, np.ndarray] = {}  # blocks, and what the readings of one network share
        out, jobs, todo = [], [], {}
        for i, r in enumerate(self.readings):
            q = self._read(loglik, ends, r.p_hmm, replication)
            blocks, keys = self._statistics(episodes, q, rep.tables[r.network], r.network, i, cache, todo)
            out.append(blocks)
            jobs.append(keys)
        if todo:  # description probabilities to decode, by key, in order of first use
            n = len(episodes.features)
            best = best_sentences(
                np.concatenate([p.reshape(-1, p.shape[-1]) for p in todo.values()]),
                list(self.world.binary_leaves),
            )
            values = {node: self.world.bn.schema.values_of(node) for node in DESCRIBED}
            reps = np.array([p.shape[0] * p.shape[1] // n for p in todo.values()])
            truth = {k: np.concatenate([np.repeat(episodes.codes[k], f) for f in reps]) for k in DESCRIBED}
            ok = agreement(best, truth, values)
            ok = np.stack([ok[a] for a in (*ASPECTS, "all")], axis=1)  # (rows, aspects)
            F = len(self.settings.fractions)
            at = 0
            for k, f in zip(todo, reps, strict=True):
                block = ok[at : at + n * f].reshape(n, f, -1)
                cache[k] = np.broadcast_to(block, (n, F, block.shape[2])).reshape(n, -1)
                at += n * f
            for blocks, keys in zip(out, jobs, strict=True):
                blocks += [cache[k] for k in keys]
        return out

    def _statistics(
        self,
        episodes: Chunk,
        q: np.ndarray,
        tables: Mapping[str, NetworkTables],
        network: str,
        reading: int,
        cache: dict[tuple, np.ndarray],
        todo: dict[tuple, np.ndarray],
    ) -> tuple[list[np.ndarray], list[tuple]]:
        """The action and effect blocks of one reading, and the keys of its description blocks, whose word
        probabilities (shape (n, f, W)) go to ``todo`` to be decoded together. Keys are shared by the
        readings of one network for the gesture-free strategies and for the hard decision, which depends
        on p_HMM only through its top action (the same under every reading unless the calibrated one is
        flat); the others carry the reading's index."""
        s, codes = self.settings, episodes.codes
        shape = {n: self.world.bn.schema.cardinality(n) for n in AFFORDANCE_NODES}
        n, F, K = q.shape
        action = codes["Action"]
        top = np.argmax(q, axis=-1).tobytes()

        def key(target: str, strat: str) -> tuple:
            shared = strat in GESTURE_FREE or strat == "hard"
            return (network, target, strat, top if strat == "hard" else b"", -1 if shared else reading)

        blocks = [np.ones((n, 1))]
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
        t = tables["effect"]
        c = t.combo(codes, [shape[x] for x in t.nodes])
        p_a, p_x = t.p_action[c], t.p_given_action[c]  # (n, K), (n, K, V)
        for strat in s.strategies_for("effect"):
            if key("effect", strat) not in cache:
                p = self._fused(strat, p_a, p_x, q, action)
                cache[key("effect", strat)] = _prediction_stats(p, codes[EFFECT], s, s.bins)
            blocks.append(cache[key("effect", strat)])
        t = tables["description"]
        c = t.combo(codes, [shape[x] for x in t.nodes])
        p_a, p_w = t.p_action[c], t.p_given_action[c]
        keys = []
        for strat in s.strategies_for("description"):
            k = key("description", strat)
            if k not in todo:
                f = 1 if strat in GESTURE_FREE else F  # the same sentence at every fraction
                todo[k] = self._fused(strat, p_a, p_w, q, action)[:, :f]
            keys.append(k)
        return blocks, keys

    def _fused(
        self, strat: str, p_a: np.ndarray, p_x: np.ndarray, q: np.ndarray, action: np.ndarray
    ) -> np.ndarray:
        """p(X) per episode and fraction, shape (n, F, V), for a target other than Action."""
        n, F, _ = q.shape
        if strat == "network":
            p = np.einsum("nk,nkv->nv", p_a, p_x)
        elif strat == "true_action":
            p = p_x[np.arange(n), action]
        else:
            return _uniform_if_undefined(fuse_tables(p_x[:, None], p_a[:, None], q, strat))
        return np.broadcast_to(p[:, None, :], (n, F, p.shape[-1]))


def _uniform_if_undefined(p: np.ndarray) -> np.ndarray:
    bad = ~np.isfinite(p).all(axis=-1)
    if bad.any():
        p = p.copy()
        p[bad] = 1.0 / p.shape[-1]
    return p


def _prediction_stats(p: np.ndarray, truth: np.ndarray, s: EvaluationSettings, bins: int = 0) -> np.ndarray:
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
    if not bins:
        return stats.reshape(n, -1)
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
