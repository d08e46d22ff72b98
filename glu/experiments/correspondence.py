"""The correspondence problem: recognising an action seen from another posture and another point of view.

The papers leave it as future work: the robot learns its actions from its own movements, and must recognise
them when a person makes them, seen from where the robot stands. This module measures how far gesture
HMMs carry over, and what invariant features (:mod:`glu.gestures.invariants`) buy and cost:

* :func:`correspondence_study` trains recognisers on the robot's own movements (``View(performer="robot")``)
  and, separately, on one human view (a person facing the camera), each with several feature sets, and
  recognises fresh human gestures under one change at a time (:func:`default_conditions`): the viewpoint
  (yaw 0–180°), a mirror image, a seated posture, body size, sensor noise, and all at once. The test
  gestures of one seed are the same movements in every condition (the generator draws a person in full
  whatever the view), so conditions and feature sets are compared on paired data;
* :func:`summarise` gives the mean accuracy over seeds with a 95 % t-interval, :func:`invariance_effects`
  the paired change of accuracy when one invariance is added (negative: the invariance costs accuracy);
* :func:`two_views` runs one action seen from two viewpoints through a raw and an invariant recogniser,
  for :func:`glu.recording.write_two_views`.

The real data's side of it, the seated taps, is :mod:`glu.experiments.seated`. Every function returns a tidy frame stamped by :func:`~glu.experiments.common.tidy`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.experiments.common import tidy
from glu.gestures.corpus import Corpus, synthetic_corpus
from glu.gestures.invariants import Invariants
from glu.gestures.recognizer import Recognizer, train_recognizer
from glu.gestures.robot import ROBOT_NOISE
from glu.gestures.synthetic import SYNTHETIC_POLICY, View, synthesize_gesture
from glu.gestures.trajectories import repair
from glu.hmm import TrainingConfig
from glu.schema import ACTIONS

FEATURE_SETS: tuple[str, ...] = (
    "raw",
    "centred",
    "centred+scaled",
    "centred+rotated",
    "centred+mirrored",
    "all",
)
"""The feature sets compared by default: raw, translation invariance, and each other invariance added to it
(they act on the displacement from the start, so in practice they need it), and all four."""
TRAIN_SOURCES: tuple[str, ...] = ("robot", "human")
STUDY_TRAINING = TrainingConfig(n_mix=1, n_iter=50, tol=1e-3)
"""The study's HMMs: one Gaussian per state (the views' shapes, not one person's path), short EM."""
"""Where the recognisers learn: the robot's own movements, or one human view (facing the camera)."""
HUMAN_NOISE = 0.01
"""Metres: sensor noise of the human gestures (camera skeleton), as the generator's default."""
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
) -> list[Condition]:
    """The study's conditions: one factor at a time away from a standing person facing the camera.

    ``normalise_body`` is the test views' feature normalisation (False: fixed constants, as the 2017
    logs, so body size shows in the features). The reference (yaw 0°) is the first condition; with
    ``robot``, the last is the robot's own movements (held out), the training domain of robot-trained
    recognisers.
    """
    base = View(yaw_deg=0.0, normalise_body=normalise_body)
    conds = [
        Condition("viewpoint", f"{y:g}°", View(yaw_deg=float(y), normalise_body=normalise_body)) for y in yaws
    ]
    if mirror:
        conds.append(
            Condition("mirror", "mirrored", View(yaw_deg=0.0, mirror=True, normalise_body=normalise_body))
        )
    if seated:
        conds.append(
            Condition("posture", "seated", View(yaw_deg=0.0, posture="seated", normalise_body=normalise_body))
        )
    conds += [
        Condition("body size", f"{s:g}", View(yaw_deg=0.0, size=float(s), normalise_body=normalise_body))
        for s in sizes
    ]
    conds += [Condition("sensor noise", f"{n * 100:g} cm", base, float(n)) for n in noises]
    if combined:
        view = View(yaw_deg=90.0, mirror=True, posture="seated", size=1.2, normalise_body=normalise_body)
        conds.append(Condition("combined", "seated, mirrored, 90°, body size 1.2", view))
    if robot:
        view = View(performer="robot", normalise_body=normalise_body)
        conds.append(Condition("performer", "the robot itself", view, ROBOT_NOISE, 0.0, 0.0))
    return conds


def training_corpus(source: str, n_per_action: int, seed: int, normalise_body: bool = False) -> Corpus:
    """The training gestures of ``source``: the robot's own movements, or one human view (facing the camera)."""
    if source == "robot":
        view = View(performer="robot", normalise_body=normalise_body)
        return synthetic_corpus(
            n_per_action, seed, view=view, noise=ROBOT_NOISE, spike_rate=0.0, dropout_rate=0.0
        )
    if source == "human":
        return synthetic_corpus(n_per_action, seed, view=View(normalise_body=normalise_body))
    raise DataError(f"unknown training source {source!r}; allowed: {', '.join(TRAIN_SOURCES)}")


def train_for(
    source: str,
    features: str | Invariants = "raw",
    n_per_action: int = 12,
    seed: int = 0,
    normalise_body: bool = False,
    config: TrainingConfig | None = None,
) -> Recognizer:
    """A recogniser trained on :func:`training_corpus` with ``config`` (default glu's)."""
    corpus = training_corpus(source, n_per_action, seed, normalise_body)
    by_action = {a: [s.xyz for s in corpus if s.action == a] for a in ACTIONS}
    meta = {"data": corpus.description}
    return train_recognizer(by_action, config, seed=seed, warn=False, features=features, meta=meta)


def _test_seed(seed: int) -> int:
    """The seed of the test gestures of study seed ``seed`` (apart from every training corpus)."""
    return int(np.random.SeedSequence([seed, 13]).generate_state(1)[0])


def _accuracies(rec: Recognizer, corpora: Sequence[Corpus]) -> list[tuple[float, dict[str, float]]]:
    """Accuracy, and per action, of ``rec`` on each corpus (every sequence scored in one batch)."""
    ll = rec.loglik_many([s.xyz for corpus in corpora for s in corpus])
    predicted = np.array(rec.actions)[np.argmax(ll, axis=1)]  # as Recognizer.classify
    out, lo = [], 0
    for corpus in corpora:
        actions = np.array([s.action for s in corpus])
        hits = predicted[lo : lo + len(corpus)] == actions
        lo += len(corpus)
        out.append(
            (float(hits.mean()), {a: float(hits[actions == a].mean()) for a in dict.fromkeys(actions)})
        )
    return out


def correspondence_study(
    train_sources: Sequence[str] = TRAIN_SOURCES,
    feature_sets: Sequence[str] = FEATURE_SETS,
    conditions: Sequence[Condition] | None = None,
    seeds: Sequence[int] = (0, 1, 2, 3, 4),
    n_train: int = 12,
    n_test: int = 10,
    *,
    config: TrainingConfig = STUDY_TRAINING,
    normalise_body: bool = False,
    invariant_settings: Mapping[str, Any] | None = None,
) -> pd.DataFrame:
    """Accuracy of recognisers trained on the robot's or one human's gestures, on human gestures seen otherwise.

    Parameters
    ----------
    train_sources : subset of :data:`TRAIN_SOURCES`
    feature_sets : invariant feature sets (names for :meth:`Invariants.parse`, e.g. ``"centred+rotated"``)
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
    mirror, posture, size, noise_m, n_test, accuracy, and accuracy_<action> per action.
    """
    conditions = list(conditions or default_conditions(normalise_body))
    settings = dict(invariant_settings or {})
    specs = [Invariants.parse(f, **settings) for f in feature_sets]
    runs, sets = [], []  # (seed, source, spec) of every recogniser, and its training set
    tests = {}
    for seed in seeds:
        tests[seed] = [
            synthetic_corpus(
                n_test,
                _test_seed(seed),
                view=c.view,
                noise=c.noise,
                spike_rate=c.spike_rate,
                dropout_rate=c.dropout_rate,
            )
            for c in conditions
        ]  # the same movements in every human condition: only the view or the sensor differs
        for source in train_sources:
            corpus = training_corpus(source, n_train, seed, normalise_body)
            by_action = {a: [s.xyz for s in corpus if s.action == a] for a in ACTIONS}
            for spec in specs:
                runs.append((seed, source, spec))
                sets.append(by_action)
    # every model of every recogniser in one batch (each as train_recognizer would train it)
    recs = train_recognizer(
        sets, config, seed=[r[0] for r in runs], features=[r[2] for r in runs], warn=False
    )
    rows = []
    for (seed, source, spec), rec in zip(runs, recs, strict=True):
        for c, test, (acc, per_action) in zip(
            conditions, tests[seed], _accuracies(rec, tests[seed]), strict=True
        ):
            rows.append(
                {
                    "seed": seed,
                    "train": source,
                    "features": spec.name,
                    "factor": c.factor,
                    "level": c.level,
                    "yaw_deg": c.view.yaw_deg,
                    "mirror": c.view.mirror,
                    "posture": c.view.posture,
                    "size": c.view.size,
                    "noise_m": c.noise,
                    "n_test": len(test),
                    "accuracy": acc,
                    **{f"accuracy_{a}": v for a, v in per_action.items()},
                }
            )
    return tidy(
        pd.DataFrame(rows),
        "correspondence_study",
        f"synthetic data: the robot's own movements and one human view → human gestures seen otherwise "
        f"({n_train} training, {n_test} test gestures per action and seed)",
        train_sources=train_sources,
        feature_sets=[s.name for s in specs],
        seeds=seeds,
        n_train=n_train,
        n_test=n_test,
        n_states=config.n_states,
        n_mix=config.n_mix,
        n_iter=config.n_iter,
        tol=config.tol,
        normalise_body=normalise_body,
        conditions=[f"{c.factor}: {c.level}" for c in conditions],
        invariant_settings=settings,
    )


def t_interval(values: Sequence[float], confidence: float = 0.95) -> tuple[float, float, float]:
    """Mean and two-sided ``confidence`` t-interval of ``values`` (NaN bounds for fewer than 2 values)."""
    from scipy import stats

    v = np.asarray(values, dtype=float)
    mean = float(v.mean()) if len(v) else float("nan")
    if len(v) < 2:
        return mean, float("nan"), float("nan")
    half = float(stats.t.ppf(0.5 + confidence / 2, len(v) - 1) * v.std(ddof=1) / np.sqrt(len(v)))
    return mean, mean - half, mean + half


def summarise(results: pd.DataFrame, confidence: float = 0.95) -> pd.DataFrame:
    """Mean accuracy over seeds with its ``confidence`` t-interval, per (train, features, condition).

    Columns: train, features, factor, level, yaw_deg, n_seeds, accuracy, ci_low, ci_high (the interval
    clipped to [0, 1]). Rows keep the order of the study.
    """
    keys = ["train", "features", "factor", "level"]
    rows = []
    for key, g in results.groupby(keys, sort=False):
        mean, lo, hi = t_interval(g["accuracy"], confidence)
        rows.append(
            {
                **dict(zip(keys, key, strict=True)),
                "yaw_deg": g["yaw_deg"].iloc[0],
                "n_seeds": len(g),
                "accuracy": mean,
                "ci_low": max(lo, 0.0) if lo == lo else lo,
                "ci_high": min(hi, 1.0) if hi == hi else hi,
            }
        )
    return tidy(
        pd.DataFrame(rows),
        "correspondence_summary",
        results.attrs.get("data_source", ""),
        confidence=confidence,
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


def invariance_effects(results: pd.DataFrame, confidence: float = 0.95) -> pd.DataFrame:
    """What adding one invariance changes: paired accuracy differences over seeds, per condition.

    For every feature set F of the study that has an invariance X and whose set without X was also run,
    ``delta = accuracy(F) − accuracy(F without X)`` on the same seed and test gestures. Columns: train,
    invariance, features, baseline, factor, level, delta, ci_low, ci_high, costs (the whole interval
    below 0: the invariance costs accuracy there), helps (the whole interval above 0).
    """
    sets = {Invariants.parse(f).name: Invariants.parse(f) for f in dict.fromkeys(results["features"])}
    keys = ["seed", "train", "factor", "level"]
    rows = []
    for name, spec in sets.items():
        for x in spec.names:
            base = Invariants(tuple(n for n in spec.names if n != x)).name
            if base not in sets:
                continue
            a = results[results["features"] == name].set_index(keys)["accuracy"]
            b = results[results["features"] == base].set_index(keys)["accuracy"]
            d = (a - b.reindex(a.index)).dropna().reset_index()
            for (train, factor, level), g in d.groupby(["train", "factor", "level"], sort=False):
                mean, lo, hi = t_interval(g["accuracy"], confidence)
                rows.append(
                    {
                        "train": train,
                        "invariance": x,
                        "features": name,
                        "baseline": base,
                        "factor": factor,
                        "level": level,
                        "delta": mean,
                        "ci_low": lo,
                        "ci_high": hi,
                        "costs": bool(hi < 0),
                        "helps": bool(lo > 0),
                    }
                )
    return tidy(
        pd.DataFrame(rows),
        "correspondence_invariance_effects",
        results.attrs.get("data_source", ""),
        confidence=confidence,
    )


# ------------------------------------------------------------------ one action, two viewpoints


@dataclass
class ViewRun:
    """One gesture seen from one viewpoint, through a raw and an invariant recogniser.

    Attributes
    ----------
    label : e.g. ``"yaw 0°"``
    view : how it was seen
    seconds : time from the first frame, shape (T,)
    skeleton : the person in the camera frame, metres, shape (T, 15, 3)
    raw : the hand features as seen, shape (T, 3)
    aligned : the invariant features of the invariant recogniser, shape (T, 3)
    actions : the recognisers' actions
    p_raw, p_aligned : ``p_HMM(A | G_1^t)`` of each recogniser, shape (T, n_actions)
    """

    label: str
    view: View
    seconds: np.ndarray
    skeleton: np.ndarray
    raw: np.ndarray
    aligned: np.ndarray
    actions: tuple[str, ...]
    p_raw: np.ndarray
    p_aligned: np.ndarray
    parameters: dict[str, object] = field(default_factory=dict)

    def curves(self) -> pd.DataFrame:
        """Tidy per-frame posteriors: columns view, recogniser, t, seconds, action, p_hmm."""
        T, A = self.p_raw.shape
        frames = []
        for name, p in (("raw", self.p_raw), ("aligned", self.p_aligned)):
            frames.append(
                pd.DataFrame(
                    {
                        "view": self.label,
                        "recogniser": name,
                        "t": np.repeat(np.arange(1, T + 1), A),
                        "seconds": np.repeat(self.seconds, A),
                        "action": np.tile(self.actions, T),
                        "p_hmm": p.ravel(),
                    }
                )
            )
        return tidy(
            pd.concat(frames, ignore_index=True),
            "correspondence_two_views",
            f"synthetic data: one gesture seen as {self.view.describe()}",
            **self.parameters,
        )


def two_views_curves(runs: Sequence[ViewRun]) -> pd.DataFrame:
    """The per-frame posteriors of every view in one tidy frame (:meth:`ViewRun.curves` concatenated)."""
    frames = [r.curves() for r in runs]
    out = pd.concat(frames, ignore_index=True)
    return tidy(
        out,
        "correspondence_two_views",
        "synthetic data: one gesture seen as " + "; ".join(r.view.describe() for r in runs),
        **frames[0].attrs["parameters"],
    )


def two_views(
    raw: Recognizer,
    invariant: Recognizer,
    action: str = "tap",
    views: Sequence[View] = (View(yaw_deg=0.0), View(yaw_deg=120.0, mirror=True)),
    seed: int = 0,
    noise: float = HUMAN_NOISE,
) -> list[ViewRun]:
    """The same synthetic gesture (one seed) seen from each of ``views``, scored frame by frame.

    ``raw`` should be a raw-feature recogniser and ``invariant`` one with invariant features; both stream
    the gesture (:meth:`Recognizer.stream`), so the posteriors are what the robot would see online.
    No spikes or dropouts, so every view has the same frames.
    """
    out = []
    for view in views:
        rng = np.random.default_rng(np.random.SeedSequence([seed, 17]))
        g = synthesize_gesture(action, rng, noise=noise, spike_rate=0.0, dropout_rate=0.0, view=view)
        traj = repair(g.trajectory(), SYNTHETIC_POLICY).pieces[0]
        X = traj.xyz
        p_raw = raw.stream().extend(X)[1]
        p_inv = invariant.stream().extend(X)[1]
        label = f"yaw {view.yaw_deg or 0:g}°" + (", mirrored" if view.mirror else "")
        out.append(
            ViewRun(
                label,
                view,
                traj.t - traj.t[0],
                g.skeleton,
                X,
                invariant.transform(X),
                raw.actions,
                p_raw,
                p_inv[:, [invariant.actions.index(a) for a in raw.actions]],
                {"action": action, "seed": seed, "noise_m": noise, "features": invariant.features.name},
            )
        )
    return out
