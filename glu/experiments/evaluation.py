"""Every fusion strategy measured on simulated episodes: what each episode contributes to each metric.

For each episode of a chunk (:mod:`glu.experiments.corpus`) and each observed fraction ``f`` of its
gesture, the gesture HMMs give ``p_HMM(A | G_1^t)`` with ``t = ⌈f·T⌉`` (one vectorised forward pass,
:class:`~glu.hmm._engine.batch.BatchScorer`; from the likelihoods as the originals, or per frame — the
condition's ``posterior``, :data:`~glu.experiments.corpus.POSTERIORS`), and each strategy predicts three
things:

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

Each prediction contributes per-episode statistics — correct (top choice right), log-loss
``−ln max(p_true, LOG_FLOOR)``, Brier ``Σ_k (p_k − y_k)²``, and for the effect the top-label calibration
bins (count, confidence, correct) — which :mod:`glu.experiments.intervals` sums with bootstrap weights.
The network is queried once per distinct evidence (:func:`network_tables`), never per episode.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from itertools import product
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.bn.inference import InferenceEngine
from glu.errors import DataError, ImpossibleEvidenceError, ModelError
from glu.experiments.corpus import (
    POSTERIORS,
    VIEWPOINTS,
    Chunk,
    Condition,
    GestureSettings,
    Scenario,
    simulate_chunk,
)
from glu.experiments.intervals import BOOT_KEY, accumulate, poisson_weights
from glu.fusion import STRATEGIES, fuse_action_tables, fuse_tables
from glu.gestures.synthetic import View
from glu.hmm import BatchScorer, p_hmm_from_loglik
from glu.language.batch import ASPECTS, agreement, best_sentences
from glu.schema import ACTIONS, AFFORDANCE_NODES

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
EFFECT = "ObjVel"
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

    def strategies_for(self, target: str) -> tuple[str, ...]:
        """The chosen strategies that predict ``target``, in :data:`EVAL_STRATEGIES` order."""
        return tuple(s for s in EVAL_STRATEGIES if s in self.strategies and s in APPLICABLE[target])


def statistic_columns(settings: EvaluationSettings) -> pd.DataFrame:
    """The per-episode statistics a chunk sums, one row per column of its statistics matrix.

    Columns: target, strategy, fraction, stat (``correct``, ``log_loss``, ``brier``; ``bin_n``,
    ``bin_confidence``, ``bin_correct`` with ``bin`` ≥ 0 for the effect; the aspects of
    :data:`glu.language.batch.ASPECTS` and ``all`` for descriptions), bin (−1 if none). Row 0 is the
    episode count (target ``episodes``).
    """
    rows: list[tuple[str, str, float, str, int]] = [("episodes", "", math.nan, "n", -1)]
    for target in TARGETS:
        for s in settings.strategies_for(target):
            for f in settings.fractions:
                if target == "description":
                    rows += [(target, s, f, a, -1) for a in (*ASPECTS, "all")]
                    continue
                rows += [(target, s, f, st, -1) for st in PREDICTION_STATS]
                if target == "effect":
                    rows += [
                        (target, s, f, st, b)
                        for b in range(settings.bins)
                        for st in ("bin_n", "bin_confidence", "bin_correct")
                    ]
    return pd.DataFrame(rows, columns=["target", "strategy", "fraction", "stat", "bin"])


class NetworkTables(NamedTuple):
    """The network's answers for every combination of observed values (queried once, used per episode).

    Attributes
    ----------
    nodes : the observed nodes, in order; an episode's combination is ``ravel_multi_index`` of its codes
    p_action : array, shape (C, K) — ``p_BN(A | X_obs)``
    p_given_action : array, shape (C, K, V) — ``p_BN(X | X_obs, A = a)`` of the target(s) (NaN rows for
        combinations of probability 0)
    """

    nodes: tuple[str, ...]
    p_action: np.ndarray
    p_given_action: np.ndarray

    def combo(self, codes: Mapping[str, np.ndarray], shape: Sequence[int]) -> np.ndarray:
        """The combination index of each episode, shape (n,)."""
        if not self.nodes:
            return np.zeros(len(next(iter(codes.values()))), dtype=np.intp)
        return np.ravel_multi_index(tuple(codes[n] for n in self.nodes), tuple(shape))


def network_tables(engine: InferenceEngine, nodes: Sequence[str], target: str) -> NetworkTables:
    """:class:`NetworkTables` for observed ``nodes``; ``target`` is a node (e.g. ObjVel) or ``"words"``."""
    schema = engine.bn.schema
    values = [schema.values_of(n) for n in nodes]
    actions = schema.values_of("Action")
    n_out = len(engine.binary_leaves) if target == "words" else schema.cardinality(target)
    combos = list(product(*values))
    p_a = np.full((len(combos), len(actions)), np.nan)
    p_x = np.full((len(combos), len(actions), n_out), np.nan)
    for c, vals in enumerate(combos):
        ev = dict(zip(nodes, vals, strict=True))
        try:
            p_a[c] = engine.query(["Action"], ev)["Action"]
        except ImpossibleEvidenceError:
            continue
        for k, a in enumerate(actions):
            full = {**ev, "Action": a}
            try:
                p_x[c, k] = (
                    engine.word_probability_array(full)
                    if target == "words"
                    else engine.query([target], full)[target]
                )
            except ImpossibleEvidenceError:
                p_x[c, k] = 0.0  # this action is impossible here: p_a is 0 for it, so the row is never used
    return NetworkTables(tuple(nodes), p_a, p_x)


@dataclass(frozen=True, eq=False)
class Evaluator:
    """Everything needed to simulate and score chunks of episodes; built once, sent to every worker.

    Attributes
    ----------
    engine : the Affordance–Words network (the world the episodes are drawn from, and the robot's model)
    scorer : the gesture recogniser, as a :class:`~glu.hmm._engine.batch.BatchScorer` (models in the order
        of :data:`glu.schema.ACTIONS`)
    settings : what is measured
    seed, chunk_size : the corpus's seed and chunk size
    scenario, gestures, views : the corpus's settings (:func:`~glu.experiments.corpus.simulate_chunk`)
    """

    engine: InferenceEngine
    scorer: BatchScorer
    settings: EvaluationSettings = EvaluationSettings()
    seed: int = 0
    chunk_size: int = 2000
    scenario: Scenario = Scenario()
    gestures: GestureSettings = GestureSettings()
    views: Mapping[str, View] = field(default_factory=lambda: dict(VIEWPOINTS))
    tables: dict[str, NetworkTables] = field(init=False, repr=False)
    columns: pd.DataFrame = field(init=False, repr=False)

    def __post_init__(self) -> None:
        names = tuple(m.name for m in self.scorer.models)
        if names != ACTIONS:
            raise ModelError(
                f"the recogniser's models must be {', '.join(ACTIONS)} in this order, not {names}"
            )
        s = self.settings
        tables = {
            "action": network_tables(self.engine, s.action_evidence, EFFECT),
            "effect": network_tables(self.engine, s.effect_evidence, EFFECT),
            "description": network_tables(self.engine, s.description_evidence, "words"),
        }
        object.__setattr__(self, "tables", tables)
        object.__setattr__(self, "columns", statistic_columns(s))

    def simulate(self, condition: Condition, chunk: int, n: int) -> Chunk:
        """The episodes of one chunk (:func:`~glu.experiments.corpus.simulate_chunk`)."""
        return simulate_chunk(
            self.engine,
            condition,
            self.seed,
            chunk,
            n,
            self.chunk_size,
            self.scenario,
            self.gestures,
            self.views,
        )

    def run_chunk(self, condition: Condition, chunk: int, n: int) -> np.ndarray:
        """Simulate and score one chunk: its statistics summed with bootstrap weights, shape (B + 1, K).

        Row 0 holds the plain sums (every weight 1), rows 1… the bootstrap replicates; column k is
        ``self.columns`` row k. The weights depend on (seed, chunk) only, so every condition and strategy
        is resampled on the same episodes (paired).
        """
        return self.run_chunks([condition], chunk, n)[0]

    def run_chunks(self, conditions: Sequence[Condition], chunk: int, n: int) -> list[np.ndarray]:
        """:meth:`run_chunk` for conditions that differ only in their posterior: one simulation for all."""
        if len({(c.noise, c.viewpoint) for c in conditions}) != 1:
            raise DataError("run_chunks: the conditions must share their noise and viewpoint")
        episodes = self.simulate(conditions[0], chunk, n)
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(BOOT_KEY, chunk)))
        weights = poisson_weights(n, self.settings.bootstrap, rng)
        return [accumulate(self.episode_statistics(episodes, c.posterior), weights) for c in conditions]

    def p_hmm(self, features: Sequence[np.ndarray], posterior: str = "likelihood") -> np.ndarray:
        """``p_HMM(A | G_1^t)`` at every observed fraction, shape (n, F, K) (``posterior``: :data:`POSTERIORS`)."""
        lengths = np.array([len(x) for x in features])
        f = np.asarray(self.settings.fractions)
        ends = np.maximum(np.ceil(np.round(f[None, :] * lengths[:, None], 9)).astype(int), 1)
        loglik = self.scorer.loglik_at(features, ends)
        if posterior == "per_frame":
            loglik = loglik / ends[:, :, None]
        elif posterior != "likelihood":
            raise DataError(f"unknown posterior {posterior!r}; allowed: {', '.join(POSTERIORS)}")
        q = p_hmm_from_loglik(loglik)
        bad = ~np.isfinite(q).all(axis=-1)
        q[bad] = 1.0 / q.shape[-1]  # every model finds the prefix impossible: no information
        return q

    def episode_statistics(self, episodes: Chunk, posterior: str = "likelihood") -> list[np.ndarray]:
        """Per-episode statistics, blocks of columns in the order of ``self.columns`` (each shape (n, k))."""
        s, codes = self.settings, episodes.codes
        shape = {n: self.engine.shape[self.engine.axis[n]] for n in AFFORDANCE_NODES}
        q = self.p_hmm(episodes.features, posterior)  # (n, F, K)
        n, F, K = q.shape
        action = codes["Action"]
        blocks = [np.ones((n, 1))]
        # action
        t = self.tables["action"]
        p_a = t.p_action[t.combo(codes, [shape[x] for x in t.nodes])]  # (n, K)
        for strat in s.strategies_for("action"):
            if strat == "gesture":
                p = q
            elif strat == "network":
                p = np.broadcast_to(p_a[:, None, :], q.shape)
            else:
                p = fuse_action_tables(p_a[:, None, :], q, strat)
            blocks.append(_prediction_stats(p, action, s))
        # effect
        t = self.tables["effect"]
        c = t.combo(codes, [shape[x] for x in t.nodes])
        p_a, p_x = t.p_action[c], t.p_given_action[c]  # (n, K), (n, K, V)
        truth = codes[EFFECT]
        for strat in s.strategies_for("effect"):
            p = self._fused(strat, p_a, p_x, q, action)
            blocks.append(_prediction_stats(p, truth, s, bins=s.bins))
        # descriptions
        t = self.tables["description"]
        c = t.combo(codes, [shape[x] for x in t.nodes])
        p_a, p_w = t.p_action[c], t.p_given_action[c]
        words = list(self.engine.binary_leaves)
        values = {node: self.engine.bn.schema.values_of(node) for node in DESCRIBED}
        truth_codes = {node: codes[node] for node in DESCRIBED}
        for strat in s.strategies_for("description"):
            probs = self._fused(strat, p_a, p_w, q, action)  # (n, F, W)
            f = 1 if strat in GESTURE_FREE else F  # the same sentence at every fraction
            best = best_sentences(probs[:, :f].reshape(n * f, -1), words)
            ok = agreement(best, {k: np.repeat(v, f) for k, v in truth_codes.items()}, values)
            ok = np.stack([ok[a].reshape(n, f) for a in (*ASPECTS, "all")], axis=2)
            blocks.append(np.broadcast_to(ok, (n, F, ok.shape[2])).reshape(n, -1))
        return blocks

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
    """correct, log-loss, Brier (and calibration bins) per episode and fraction, shape (n, F · k)."""
    n, F, V = p.shape
    p = _uniform_if_undefined(p)
    y = np.broadcast_to(truth[:, None], (n, F))
    p_true = np.take_along_axis(p, y[..., None], axis=-1)[..., 0]
    top = np.argmax(p, axis=-1)
    correct = (top == y).astype(float)
    log_loss = -np.log(np.maximum(p_true, s.log_floor))
    brier = (p**2).sum(axis=-1) - 2 * p_true + 1.0
    cols = [correct, log_loss, brier]
    if bins:
        conf = np.take_along_axis(p, top[..., None], axis=-1)[..., 0]
        b = np.minimum((conf * bins).astype(int), bins - 1)
        onehot = b[..., None] == np.arange(bins)  # (n, F, bins)
        per_bin = np.stack([onehot, onehot * conf[..., None], onehot * correct[..., None]], axis=-1)
        return np.concatenate(
            [np.stack(cols, axis=-1), per_bin.reshape(n, F, bins * 3).astype(float)], axis=-1
        ).reshape(n, -1)
    return np.stack(cols, axis=-1).reshape(n, -1)


def describe_settings(evaluator: Evaluator) -> dict[str, Any]:
    """The settings of an evaluator as plain data (for result files)."""
    s = evaluator.settings
    return {
        "fractions": list(s.fractions),
        "strategies": list(s.strategies),
        "action_evidence": list(s.action_evidence),
        "effect_evidence": list(s.effect_evidence),
        "description_evidence": list(s.description_evidence),
        "bins": s.bins,
        "bootstrap": s.bootstrap,
        "log_floor": s.log_floor,
        "seed": evaluator.seed,
        "chunk_size": evaluator.chunk_size,
        "scenario": evaluator.scenario.as_dict(),
        "gestures": {
            "spike_rate": evaluator.gestures.spike_rate,
            "dropout_rate": evaluator.gestures.dropout_rate,
        },
        "views": {
            k: {"yaw_deg": v.yaw_deg, "mirror": v.mirror, "posture": v.posture, "size": v.size}
            for k, v in evaluator.views.items()
        },
    }
