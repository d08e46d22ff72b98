"""The correspondence problem: recognising an action seen from another posture and another point of view.

The papers leave it as future work: the robot learns its actions from its own movements, and must recognise
them when a person makes them, seen from where the robot stands. This module measures how far gesture
HMMs carry over, and what invariant features (:mod:`glu.gestures.invariants`) and the body frame of the
shoulder line (:func:`glu.gestures.features.to_body_frame`) buy and cost:

* :func:`correspondence_study` trains recognisers on the robot's own movements (``View(performer="robot")``)
  and, separately, on one human view (standard people facing the camera), each with several feature sets,
  and recognises fresh human gestures under one change at a time (:func:`default_conditions`): the
  viewpoint (yaw 0–180°) seen by an ideal skeleton tracker and by one that occludes
  (:func:`glu.gestures.views.track`: it loses the far shoulder side-on and swaps left and right from
  behind, as a real depth camera's tracker does), a mirror image, a seated posture, body size, sensor noise,
  and all at once. The test people are **not** the training ones seen otherwise: each has an arm length and
  a movement style of their own (``View.variety``), and the sensor noise is added to what the camera sees,
  so no feature set undoes a test view by construction. The test gestures of one seed are the same people in
  every condition, so conditions and feature sets are compared on paired data;
* :func:`summarise` gives the accuracy pooled over seeds with a two-level bootstrap interval (over the
  seeds, and the test gestures within each: :func:`glu.stats.two_level_sums`); :func:`invariance_effects`
  the paired change of accuracy when one invariance is added (negative: it costs accuracy), with a
  bootstrap p-value adjusted with the whole table's (Benjamini–Hochberg: one family).

One gesture seen from two viewpoints is :mod:`glu.studies.correspondence.two_views`; the real data's side of
it, the seated taps, :mod:`glu.studies.correspondence.nested` and :mod:`glu.studies.correspondence.seated`.
Every function returns a tidy frame stamped by :func:`~glu.tidy.tidy`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.gestures.corpus import Corpus, LabelledSequence
from glu.gestures.feature_sets import FEATURE_SET_NAMES, FeatureSet
from glu.gestures.invariants import Invariants
from glu.gestures.recognizer import Recognizer, train_recognizer
from glu.gestures.robot import ROBOT_NOISE
from glu.gestures.synthetic import View
from glu.gestures.synthetic_batch import gesture_features
from glu.hmm import TrainingConfig
from glu.schema import ACTIONS
from glu.stats import (
    HIGHER_IS_BETTER,
    LEVEL,
    adjust,
    adjusted_verdict,
    bootstrap_p_value,
    percentile_interval,
    two_level_sums,
    verdict,
)
from glu.tidy import tidy

FEATURE_SETS: tuple[str, ...] = (
    "raw",
    "centred",
    "centred+scaled",
    "centred+rotated",
    "centred+mirrored",
    "all",
    "body",
    "body+centred",
)
"""The feature sets compared by default: raw, translation invariance, and each other invariance added to it
(they act on the displacement from the start, so in practice they need it), all four; and the body frame
of the shoulder line (``body``), alone and start-centred — the rotation ``rotated`` makes from the
movement's heading, made instead from the body."""
STUDY_FEATURE_NAMES: tuple[str, ...] = FEATURE_SET_NAMES
"""Every feature set the study can compare (:data:`glu.gestures.feature_sets.FEATURE_SET_NAMES`): those of
:data:`glu.gestures.invariants.FEATURE_NAMES`, and each in the shoulder line's frame (``body``)."""
VARIETY = 1.0
"""How far the test people's arm lengths and movement styles differ from the training people's."""
BOOTSTRAP = 1000
"""Two-level bootstrap replicates of the study's intervals."""
TRAIN_SOURCES: tuple[str, ...] = ("robot", "human")
"""Where the recognisers learn: the robot's own movements, or one human view (facing the camera)."""
STUDY_TRAINING = TrainingConfig(n_mix=1, n_iter=50, tol=1e-3)
"""The study's HMMs: one Gaussian per state (the views' shapes, not one person's path), short EM."""
HUMAN_NOISE = 0.01
"""Metres: sensor noise of the human gestures (camera skeleton), as the generator's default."""
OCCLUDED = "viewpoint, occluding tracker"
"""The factor of the turns seen through the occluding tracker (:func:`glu.gestures.views.track`)."""
REFERENCE = ("viewpoint", "0°")
"""The condition every other one changes: a standing person facing the camera."""


@dataclass(frozen=True)
class Condition:
    """One test condition: a change of the human view (or of the sensor noise) from the reference.

    Attributes
    ----------
    factor : what changes (``viewpoint``, ``mirror``, ``posture``, ``body size``, ``sensor noise``,
        ``combined``, or ``performer`` for the robot's own movements)
    level : its value, as text (``"90°"``, ``"seated"``, ``"0.8"``, …)
    view : how the test gestures are seen
    noise, spike_rate, dropout_rate : the sensor of the test gestures (noise in metres)
    """

    factor: str
    level: str
    view: View
    noise: float = HUMAN_NOISE
    spike_rate: float = 0.005
    dropout_rate: float = 0.2


def default_conditions(
    normalise_body: bool = False,
    yaws: Sequence[float] = (0, 30, 60, 90, 120, 150, 180),
    sizes: Sequence[float] = (0.8, 1.25),
    noises: Sequence[float] = (0.03, 0.06),
    mirror: bool = True,
    seated: bool = True,
    combined: bool = True,
    robot: bool = True,
    variety: float = VARIETY,
    occluding: bool = True,
) -> list[Condition]:
    """The study's conditions: one factor at a time away from a standing person facing the camera.

    ``normalise_body`` is the test views' feature normalisation (False: fixed constants, as the 2017
    logs, so body size shows in the features); ``variety`` how far the test people differ from the
    training ones in arm length and movement style (``View.variety``). The reference (yaw 0°) is the
    first condition; with ``occluding``, every turn but 0° is seen a second time through the occluding
    tracker (factor :data:`OCCLUDED`; at 0° it sees what the ideal one does); with ``robot``, the last is
    the robot's own movements (held out), the training domain of robot-trained recognisers.
    """

    def view(**kw: Any) -> View:
        return View(yaw_deg=kw.pop("yaw_deg", 0.0), normalise_body=normalise_body, variety=variety, **kw)

    conds = [Condition("viewpoint", f"{y:g}°", view(yaw_deg=float(y))) for y in yaws]
    if occluding:
        turned = [float(y) for y in yaws if y % 360]
        conds += [Condition(OCCLUDED, f"{y:g}°", view(yaw_deg=y, tracker="occluding")) for y in turned]
    if mirror:
        conds.append(Condition("mirror", "mirrored", view(mirror=True)))
    if seated:
        conds.append(Condition("posture", "seated", view(posture="seated")))
    conds += [Condition("body size", f"{s:g}", view(size=float(s))) for s in sizes]
    conds += [Condition("sensor noise", f"{n * 100:g} cm", view(), float(n)) for n in noises]
    if combined:
        both = view(yaw_deg=90.0, mirror=True, posture="seated", size=1.2)
        conds.append(Condition("combined", "seated, mirrored, 90°, body size 1.2", both))
    if robot:
        view = View(performer="robot", normalise_body=normalise_body)
        conds.append(Condition("performer", "the robot itself", view, ROBOT_NOISE, 0.0, 0.0))
    return conds


def gestures(
    n_per_action: int,
    seed: int,
    view: View,
    noise: float = HUMAN_NOISE,
    spike_rate: float = 0.005,
    dropout_rate: float = 0.2,
) -> Corpus:
    """``n_per_action`` synthetic gestures per action seen as ``view``: the sequences of
    :func:`glu.gestures.corpus.synthetic_corpus` with the same arguments, computed in one batch."""
    n = n_per_action * len(ACTIONS)
    actions = [ACTIONS[i % len(ACTIONS)] for i in range(n)]
    rngs = [np.random.default_rng(c) for c in np.random.SeedSequence(seed).spawn(n)]
    batch = gesture_features(
        actions, rngs, noise=noise, spike_rate=spike_rate, dropout_rate=dropout_rate, view=view
    )
    seqs = [
        LabelledSequence(a, x, f"synthetic-{i}", 1, len(x))
        for i, (a, x) in enumerate(zip(actions, batch.features, strict=True))
    ]
    return Corpus(
        seqs, f"synthetic data: gestures (seed {seed}, {n_per_action} per action, {view.describe()})"
    )


def training_corpus(
    source: str, n_per_action: int, seed: int, normalise_body: bool = False, body_frame: bool = False
) -> Corpus:
    """The training gestures of ``source``: the robot's own movements, or one human view (standard people
    facing the camera); in the shoulder line's frame with ``body_frame``."""
    if source == "robot":
        view = View(performer="robot", normalise_body=normalise_body, body_frame=body_frame)
        return gestures(n_per_action, seed, view, ROBOT_NOISE, 0.0, 0.0)
    if source == "human":
        return gestures(n_per_action, seed, View(normalise_body=normalise_body, body_frame=body_frame))
    raise DataError(f"unknown training source {source!r}; allowed: {', '.join(TRAIN_SOURCES)}")


def train_for(
    source: str,
    features: str | Invariants = "raw",
    n_per_action: int = 12,
    seed: int = 0,
    normalise_body: bool = False,
    config: TrainingConfig | None = None,
) -> Recognizer:
    """A recogniser trained on :func:`training_corpus` with ``config`` (default glu's); ``features`` an
    :class:`Invariants` name (torso frame)."""
    corpus = training_corpus(source, n_per_action, seed, normalise_body)
    meta = {"data": corpus.description}
    return train_recognizer(_by_action(corpus), config, seed=seed, warn=False, features=features, meta=meta)


def _by_action(corpus: Corpus) -> dict[str, list[np.ndarray]]:
    """A training set: each action's sequences of ``corpus``."""
    return {a: [s.xyz for s in corpus if s.action == a] for a in ACTIONS}


def _test_seed(seed: int) -> int:
    """The seed of the test gestures of study seed ``seed`` (apart from every training corpus)."""
    return int(np.random.SeedSequence([seed, 13]).generate_state(1)[0])


def _outcomes(rec: Recognizer, corpora: Sequence[Corpus]) -> list[np.ndarray]:
    """Whether ``rec`` recognises each gesture of each corpus (every sequence scored in one batch)."""
    ll = rec.loglik_many([s.xyz for corpus in corpora for s in corpus])
    predicted = np.array(rec.actions)[np.argmax(ll, axis=1)]  # as Recognizer.classify
    hits = predicted == np.array([s.action for corpus in corpora for s in corpus])
    return np.split(hits, np.cumsum([len(corpus) for corpus in corpora])[:-1])


def correspondence_study(
    train_sources: Sequence[str] = TRAIN_SOURCES,
    feature_sets: Sequence[str] = FEATURE_SETS,
    conditions: Sequence[Condition] | None = None,
    seeds: Sequence[int] = tuple(range(10)),
    n_train: int = 12,
    n_test: int = 10,
    *,
    config: TrainingConfig = STUDY_TRAINING,
    normalise_body: bool = False,
    invariant_settings: Mapping[str, Any] | None = None,
) -> pd.DataFrame:
    """Accuracy of recognisers trained on the robot's or one human's gestures, on human gestures seen
    otherwise.

    Parameters
    ----------
    train_sources : subset of :data:`TRAIN_SOURCES`
    feature_sets : feature sets (:class:`~glu.gestures.feature_sets.FeatureSet`: ``"centred+rotated"``,
        ``"body+centred"``, …)
    conditions : test conditions (default :func:`default_conditions` with ``normalise_body``)
    seeds : one training corpus, EM initialisation and test set per seed
    n_train, n_test : gestures per action for training and for each test condition
    config : the HMMs (Q, M) and EM (:func:`glu.hmm.train`; default :data:`STUDY_TRAINING`)
    normalise_body : the features' normalisation (False: fixed constants, as the 2017 logs)
    invariant_settings : ``lock_radius``, ``min_scale``, ``anchor_frames`` of :class:`Invariants`, if not the
        defaults

    Returns
    -------
    One row per (seed, train, features, condition): seed, train, features, factor, level, yaw_deg,
    mirror, posture, size, noise_m, n_test, accuracy, accuracy_<action> per action, and outcomes (one
    character per test gesture, in order: ``1`` recognised, ``0`` not; the two-level bootstrap resamples
    them).
    """
    conditions = list(conditions or default_conditions(normalise_body))
    settings = dict(invariant_settings or {})
    specs = [FeatureSet.parse(f) for f in feature_sets]
    specs = [(body, Invariants.parse(inv, **settings)) for body, inv in specs]
    frames = sorted({body for body, _ in specs})
    tests = {(seed, body): _test_sets(conditions, n_test, seed, body) for seed in seeds for body in frames}
    runs, sets = _training_runs(train_sources, specs, seeds, n_train, normalise_body)
    # every model of every recogniser in one batch (each as train_recognizer would train it)
    recs = train_recognizer(
        sets, config, seed=[r[0] for r in runs], features=[r[3] for r in runs], warn=False
    )
    rows = []
    for (seed, source, body, inv), rec in zip(runs, recs, strict=True):
        test = tests[seed, body]
        for c, corpus, hits in zip(conditions, test, _outcomes(rec, test), strict=True):
            rows.append(_row(seed, source, FeatureSet(body, inv).name, c, corpus, hits))
    order = {name: k for k, name in enumerate(FeatureSet(b, i).name for b, i in specs)}
    frame = pd.DataFrame(rows)
    frame = frame.sort_values(
        ["seed", "train", "features"],
        key=lambda c: c.map(order) if c.name == "features" else c,
        kind="stable",
    )
    return tidy(
        frame.reset_index(drop=True),
        "correspondence_study",
        f"synthetic data: the robot's own movements and one human view → other people seen otherwise "
        f"({n_train} training, {n_test} test gestures per action and seed)",
        train_sources=train_sources,
        feature_sets=[FeatureSet(b, i).name for b, i in specs],
        seeds=seeds,
        n_train=n_train,
        n_test=n_test,
        n_states=config.n_states,
        n_mix=config.n_mix,
        n_iter=config.n_iter,
        tol=config.tol,
        normalise_body=normalise_body,
        conditions=[f"{c.factor}: {c.level}" for c in conditions],
        variety=sorted({c.view.variety for c in conditions}),
        invariant_settings=settings,
    )


def _test_sets(conditions: Sequence[Condition], n_test: int, seed: int, body: bool) -> list[Corpus]:
    """One seed's test gestures under every condition: the same people in each, only the view or the
    sensor differs."""
    return [
        gestures(
            n_test, _test_seed(seed), replace(c.view, body_frame=body), c.noise, c.spike_rate, c.dropout_rate
        )
        for c in conditions
    ]


def _training_runs(
    train_sources: Sequence[str],
    specs: Sequence[tuple[bool, Invariants]],
    seeds: Sequence[int],
    n_train: int,
    normalise_body: bool,
) -> tuple[list[tuple[int, str, bool, Invariants]], list[dict[str, list[np.ndarray]]]]:
    """(seed, source, body, invariants) of every recogniser, and its training set (action → sequences)."""
    runs, sets = [], []
    for seed in seeds:
        for source in train_sources:
            for body in sorted({b for b, _ in specs}):
                by_action = _by_action(training_corpus(source, n_train, seed, normalise_body, body))
                for b, inv in specs:
                    if b == body:
                        runs.append((seed, source, body, inv))
                        sets.append(by_action)
    return runs, sets


def _row(seed: int, source: str, features: str, c: Condition, corpus: Corpus, hits: np.ndarray) -> dict:
    """One (seed, train, features, condition) row of :func:`correspondence_study`."""
    actions = np.array([s.action for s in corpus])
    return {
        "seed": seed,
        "train": source,
        "features": features,
        "factor": c.factor,
        "level": c.level,
        "yaw_deg": c.view.yaw_deg,
        "tracker": c.view.tracker,
        "mirror": c.view.mirror,
        "posture": c.view.posture,
        "size": c.view.size,
        "noise_m": c.noise,
        "n_test": len(corpus),
        "accuracy": float(hits.mean()),
        **{f"accuracy_{a}": float(hits[actions == a].mean()) for a in dict.fromkeys(actions)},
        "outcomes": "".join("1" if h else "0" for h in hits),
    }


def _outcome_matrix(text: pd.Series) -> list[np.ndarray]:
    """Each row's ``outcomes`` as a 0/1 array."""
    return [np.frombuffer(t.encode(), dtype=np.uint8) - ord("0") for t in text]


def summarise(results: pd.DataFrame, replicates: int = BOOTSTRAP, seed: int = 0) -> pd.DataFrame:
    """Accuracy pooled over seeds with its two-level bootstrap interval, per (train, features, condition).

    The interval resamples the seeds, then each seed's test gestures
    (:func:`glu.stats.two_level_sums`); it has width 0 only when every gesture
    of every seed was recognised alike. Columns: train, features, factor, level, yaw_deg, n_seeds, accuracy,
    ci_low, ci_high, seed_min, seed_max (the seeds' own accuracies). Rows keep the order of the study.
    """
    keys = ["train", "features", "factor", "level"]
    rows = []
    for key, g in results.groupby(keys, sort=False):
        rng = np.random.default_rng(np.random.SeedSequence([seed, len(rows)]))
        stats = [np.stack([np.ones(len(o)), o], axis=1) for o in _outcome_matrix(g["outcomes"])]
        sums = two_level_sums(stats, replicates, rng)
        with np.errstate(invalid="ignore"):  # a replicate that drew no gesture is left out
            lo, hi = percentile_interval((sums[1:, 1] / sums[1:, 0])[:, None])
        rows.append(
            {
                **dict(zip(keys, key, strict=True)),
                "yaw_deg": g["yaw_deg"].iloc[0],
                "n_seeds": len(g),
                "accuracy": sums[0, 1] / sums[0, 0],
                "ci_low": float(lo[0]),
                "ci_high": float(hi[0]),
                "seed_min": g["accuracy"].min(),
                "seed_max": g["accuracy"].max(),
            }
        )
    return tidy(
        pd.DataFrame(rows),
        "correspondence_summary",
        results.attrs.get("data_source", ""),
        interval=f"{LEVEL:.0%} two-level bootstrap over seeds and test gestures ({replicates} replicates)",
        **results.attrs.get("parameters", {}),
    )


def main_table(summary: pd.DataFrame, train: str) -> pd.DataFrame:
    """One training source's summary as a table: one row per condition, one column per feature set,
    cells ``"0.93 [0.88, 0.98]"`` (mean accuracy and its interval)."""
    s = summary[summary["train"] == train].copy()
    if s.empty:
        raise DataError(f"no results for training source {train!r}")
    s["cell"] = [
        f"{a:.2f}" + ("" if lo != lo else f" [{lo:.2f}, {hi:.2f}]")
        for a, lo, hi in zip(s["accuracy"], s["ci_low"], s["ci_high"], strict=True)
    ]
    s["condition"] = s["factor"] + ": " + s["level"]
    table = s.pivot(index="condition", columns="features", values="cell")
    order = list(dict.fromkeys(s["condition"]))
    return table.loc[order, list(dict.fromkeys(s["features"]))]


def invariance_effects(results: pd.DataFrame, replicates: int = BOOTSTRAP, seed: int = 0) -> pd.DataFrame:
    """What adding one invariance changes: paired accuracy differences, per condition, adjusted for their
    number.

    For every feature set F of the study that has an invariance X and whose set without X was also run
    (in the same frame), ``delta = accuracy(F) − accuracy(F without X)`` on the same seeds and test
    gestures, with a two-level bootstrap interval of the paired difference and its bootstrap p-value; the
    p-values of the whole table are one family, adjusted by Benjamini–Hochberg. Columns: train,
    invariance, features, baseline, factor, level, delta, ci_low, ci_high, p_value, verdict (``better``,
    ``worse``, ``no difference``: the interval alone), p_adjusted, verdict_adjusted, costs and helps (the
    adjusted verdict: the invariance costs, or buys, accuracy there).
    """
    names = list(dict.fromkeys(results["features"]))
    sets = {n: FeatureSet.parse(n) for n in names}
    keys = ["seed", "train", "factor", "level"]
    rows = []
    for name, (body, spec) in sets.items():
        for x in spec.names:
            base = FeatureSet(body, Invariants(tuple(n for n in spec.names if n != x))).name
            if base not in sets:
                continue
            a = results[results["features"] == name].set_index(keys)["outcomes"]
            b = results[results["features"] == base].set_index(keys)["outcomes"].reindex(a.index)
            pairs = pd.DataFrame({"a": a, "b": b}).dropna().reset_index()
            for (train, factor, level), g in pairs.groupby(["train", "factor", "level"], sort=False):
                rng = np.random.default_rng(np.random.SeedSequence([seed, len(rows)]))
                rows.append(
                    {
                        "train": train,
                        "invariance": x,
                        "features": name,
                        "baseline": base,
                        "factor": factor,
                        "level": level,
                        **_paired(g["a"], g["b"], replicates, rng),
                    }
                )
    frame = pd.DataFrame(rows)
    if len(frame):
        frame["p_adjusted"] = adjust(frame["p_value"].to_numpy(dtype=float), "bh")
        frame["verdict_adjusted"] = [
            adjusted_verdict(d, p) for d, p in zip(frame["delta"], frame["p_adjusted"], strict=True)
        ]
        frame["costs"] = frame["verdict_adjusted"] == "worse"
        frame["helps"] = frame["verdict_adjusted"] == "better"
    return tidy(
        frame,
        "correspondence_invariance_effects",
        results.attrs.get("data_source", ""),
        interval=f"{LEVEL:.0%} two-level paired bootstrap ({replicates} replicates); verdicts adjusted by "
        "Benjamini–Hochberg over the table",
    )


def _paired(a: pd.Series, b: pd.Series, replicates: int, rng: np.random.Generator) -> dict[str, Any]:
    """The paired difference of two feature sets' outcomes (per seed, the test gestures' 0/1 strings): its
    estimate, two-level interval, bootstrap p-value and unadjusted verdict."""
    stats = [
        np.stack([np.ones(len(u)), u, v], axis=1)
        for u, v in zip(_outcome_matrix(a), _outcome_matrix(b), strict=True)
    ]
    sums = two_level_sums(stats, replicates, rng)
    with np.errstate(invalid="ignore"):  # a replicate that drew no gesture is left out
        d = (sums[:, 1] - sums[:, 2]) / sums[:, 0]
    lo, hi = (float(v[0]) for v in percentile_interval(d[1:, None]))
    return {
        "delta": float(d[0]),
        "ci_low": lo,
        "ci_high": hi,
        "p_value": float(bootstrap_p_value(d)),
        "verdict": verdict(lo, hi, HIGHER_IS_BETTER["accuracy"]),
    }
