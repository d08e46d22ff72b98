"""Evaluation of gesture recognition: cross-validation on synthetic gestures, real recordings, original
models.

Every function returns a tidy pandas DataFrame (one row per test sequence, or per condition) stamped by
:func:`~glu.tidy.tidy`, so numbers quoted anywhere are computed, never typed. The labelled
sequences come from :mod:`glu.gestures.corpus`; training settings are a
:class:`glu.hmm.TrainingConfig` (default: glu's) and the invariant features the recogniser uses
(:class:`glu.gestures.invariants.Invariants`, default raw).

* :func:`cross_validate` — stratified k-fold: train a recogniser on k-1 folds, classify the held-out fold;
  :func:`confusion_matrix` and :func:`accuracy` summarise the predictions;
* :func:`accuracy_vs_noise` — k-fold accuracy as the sensor noise grows;
* :func:`leave_one_out` — on the real segments, hold out one recording (or one segment) at a time;
* :func:`original_scores` — the original 2013 models on the five original test segments;
* :func:`anticipation_banks` — notebook 08's HMMs: the originals', and trained here by both recipes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import binomtest

from glu.data.source import DataSource
from glu.errors import DataError
from glu.gestures.corpus import LabelledSequence, gesture_sequences, original_test_segments, synthetic_corpus
from glu.gestures.invariants import Invariants
from glu.gestures.recognizer import Recognizer, load_original_models, train_recognizer
from glu.hmm import TrainingConfig, p_hmm_from_loglik
from glu.schema import ACTIONS
from glu.tidy import corpus_source, model_source, tidy, training_parameters

Features = Invariants | str | None


def stratified_folds(labels: Sequence[str], k: int, seed: int = 0) -> np.ndarray:
    """Fold number (0 … k-1) of each item, shape (n,): each label's items shuffled (seeded), dealt in turn.

    scikit-learn's ``StratifiedKFold(shuffle=True)`` makes folds of the same kind from its own random state,
    so the same seed gives other folds there; glu keeps its own to keep its cross-validation numbers.
    """
    labels = list(labels)
    if k < 2:
        raise DataError(f"k={k}: cross-validation needs at least 2 folds")
    rng = np.random.default_rng(seed)
    fold = np.empty(len(labels), dtype=int)
    for lab in sorted(set(labels)):
        idx = np.flatnonzero(np.array(labels) == lab)
        if len(idx) < k:
            raise DataError(f"{len(idx)} sequences of {lab!r} cannot fill {k} folds")
        fold[rng.permutation(idx)] = np.arange(len(idx)) % k
    return fold


def _by_action(seqs: Sequence[LabelledSequence], actions: Sequence[str]) -> dict[str, list[np.ndarray]]:
    by_action = {a: [s.xyz for s in seqs if s.action == a] for a in actions}
    return {a: v for a, v in by_action.items() if v}


def _train_all(
    sets: Sequence[tuple[Sequence[LabelledSequence], Sequence[str]]],
    seed: int,
    config: TrainingConfig | None,
    features: Features,
) -> list[Recognizer]:
    """One recogniser per (training set, actions), every model trained in one batch."""
    sets = [_by_action(s, a) for s, a in sets]
    return train_recognizer(sets, config, seed=seed, features=features, warn=False)


def _predict_rows(rec: Recognizer, test: Sequence[LabelledSequence], **extra: Any) -> list[dict[str, Any]]:
    rows = []
    for s, ll in zip(test, rec.loglik_many([s.xyz for s in test]), strict=True):
        p = p_hmm_from_loglik(ll)
        row = {
            **extra,
            "recording": s.recording,
            "start": s.start,
            "end": s.end,
            "n_frames": len(s.xyz),
            "action": s.action,
            "predicted": rec.actions[int(np.argmax(ll))],
        }
        row.update({f"loglik_{a}": float(v) for a, v in zip(rec.actions, ll, strict=True)})
        row.update({f"p_hmm_{a}": float(v) for a, v in zip(rec.actions, p, strict=True)})
        row["correct"] = row["predicted"] == s.action
        row["converged"] = all(r.converged for r in rec.reports.values())
        rows.append(row)
    return rows


def cross_validate(
    sequences: Sequence[LabelledSequence],
    k: int = 5,
    seed: int = 0,
    config: TrainingConfig | None = None,
    features: Features = None,
) -> pd.DataFrame:
    """Stratified k-fold cross-validation: one row per sequence with its fold, prediction and scores.

    ``config`` and ``features``: how each fold's recogniser is trained (default: glu's, raw features).
    Columns: fold, recording, start, end, n_frames, action, predicted, loglik_<a>, p_hmm_<a>, correct,
    converged.
    """
    splits = _folds(sequences, k, seed)
    actions = _actions(sequences)
    recs = _train_all([(tr, actions) for tr, _ in splits], seed, config, features)
    return _cv_frame(sequences, splits, recs, k, seed, training_parameters(config, features))


def _actions(sequences: Sequence[LabelledSequence]) -> tuple[str, ...]:
    return tuple(dict.fromkeys(s.action for s in sequences))


def _folds(
    sequences: Sequence[LabelledSequence], k: int, seed: int
) -> list[tuple[list[LabelledSequence], list[LabelledSequence]]]:
    """(training, test) sequences of each of the k folds."""
    folds = stratified_folds([s.action for s in sequences], k, seed)
    return [
        (
            [s for s, g in zip(sequences, folds, strict=True) if g != f],
            [s for s, g in zip(sequences, folds, strict=True) if g == f],
        )
        for f in range(k)
    ]


def _cv_frame(
    sequences: Sequence[LabelledSequence],
    splits: list[tuple[list[LabelledSequence], list[LabelledSequence]]],
    recs: Sequence[Recognizer],
    k: int,
    seed: int,
    stamp: dict[str, Any],
) -> pd.DataFrame:
    rows = []
    for f, ((_, te), rec) in enumerate(zip(splits, recs, strict=True)):
        rows += _predict_rows(rec, te, fold=f)
    return tidy(pd.DataFrame(rows), "hmm_cross_validation", corpus_source(sequences), k=k, seed=seed, **stamp)


def confusion_matrix(predictions: pd.DataFrame, actions: Sequence[str] | None = None) -> pd.DataFrame:
    """Counts of (true action, predicted action): rows ``action``, columns ``predicted``."""
    actions = list(actions) if actions is not None else list(dict.fromkeys(predictions["action"]))
    cm = pd.crosstab(
        pd.Categorical(predictions["action"], categories=actions),
        pd.Categorical(predictions["predicted"], categories=actions),
        rownames=["action"],
        colnames=["predicted"],
        dropna=False,
    )
    return cm


def accuracy(predictions: pd.DataFrame) -> float:
    """The fraction of correct predictions (NaN if there are none)."""
    return float(predictions["correct"].mean()) if len(predictions) else float("nan")


def wilson_interval(correct: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """The Wilson score interval of a proportion: ``correct`` successes of ``n`` (NaN, NaN if n = 0)."""
    if n == 0:
        return float("nan"), float("nan")
    ci = binomtest(int(correct), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


def accuracy_vs_noise(
    noise_levels: Sequence[float] = (0.0, 0.01, 0.02, 0.04, 0.08),
    n_per_action: int = 20,
    k: int = 5,
    seed: int = 0,
    actions: tuple[str, ...] = ACTIONS,
    config: TrainingConfig | None = None,
    features: Features = None,
) -> pd.DataFrame:
    """k-fold accuracy on synthetic corpora with growing sensor noise (metres, std on every joint).

    One row per noise level: noise_m, n_sequences, k, accuracy with its 95 % Wilson interval (ci_low,
    ci_high), and accuracy_<action>, ci_low_<action>, ci_high_<action> per action. The corpora share the
    seed, so only the noise differs between rows.
    """
    corpora = [synthetic_corpus(n_per_action, seed, actions=actions, noise=noise) for noise in noise_levels]
    splits = [_folds(c, k, seed) for c in corpora]
    recs = iter(
        _train_all(
            [(tr, _actions(c)) for c, sp in zip(corpora, splits, strict=True) for tr, _ in sp],
            seed,
            config,
            features,
        )
    )
    stamp = training_parameters(config, features)
    rows = []
    for noise, corpus, sp in zip(noise_levels, corpora, splits, strict=True):
        pred = _cv_frame(corpus, sp, [next(recs) for _ in sp], k, seed, stamp)
        row = {"noise_m": float(noise), "n_sequences": len(pred), "k": k, "accuracy": accuracy(pred)}
        row["ci_low"], row["ci_high"] = wilson_interval(int(pred["correct"].sum()), len(pred))
        for a in actions:
            mine = pred[pred["action"] == a]
            row[f"accuracy_{a}"] = accuracy(mine)
            row[f"ci_low_{a}"], row[f"ci_high_{a}"] = wilson_interval(int(mine["correct"].sum()), len(mine))
        row["all_converged"] = bool(pred["converged"].all())
        rows.append(row)
        source = pred.attrs["data_source"]
    return tidy(
        pd.DataFrame(rows),
        "hmm_accuracy_vs_noise",
        source,
        noise_levels=noise_levels,
        n_per_action=n_per_action,
        k=k,
        seed=seed,
        **stamp,
    )


def leave_one_out(
    sequences: Sequence[LabelledSequence],
    by: str = "recording",
    seed: int = 0,
    config: TrainingConfig | None = None,
    features: Features = None,
) -> pd.DataFrame:
    """Hold out one recording (``by="recording"``) or one segment (``by="segment"``) at a time.

    Models are trained on everything else. A held-out sequence whose action has no training sequence
    left cannot be recognised; it is reported with ``testable = False`` and ``predicted`` missing rather
    than counted as an error. Columns as :func:`cross_validate`, plus held_out and testable.
    """
    if by not in ("recording", "segment"):
        raise DataError(f"by={by!r}; allowed: 'recording', 'segment'")
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    keys = [
        s.recording if by == "recording" else f"{s.recording}:{s.start}-{s.end}#{i}"
        for i, s in enumerate(sequences)
    ]
    held = []  # (key, test, training) of every held-out key
    for key in dict.fromkeys(keys):
        te = [s for s, g in zip(sequences, keys, strict=True) if g == key]
        tr = [s for s, g in zip(sequences, keys, strict=True) if g != key]
        held.append((key, te, tr))
    trainable = [h for h in held if any(s.action in {t.action for t in h[2]} for s in h[1])]
    recs = dict(
        zip(
            [h[0] for h in trainable],
            _train_all([(h[2], actions) for h in trainable], seed, config, features),
            strict=True,
        )
    )
    rows = []
    for key, te, tr in held:
        trained_actions = {s.action for s in tr}
        testable = [s for s in te if s.action in trained_actions]
        if testable:
            rows += _predict_rows(recs[key], testable, held_out=key, testable=True)
        rows += [
            {"held_out": key, "testable": False, "recording": s.recording, "start": s.start, "end": s.end}
            | {"n_frames": len(s.xyz), "action": s.action, "predicted": None, "correct": False}
            for s in te
            if s.action not in trained_actions
        ]
    return tidy(
        pd.DataFrame(rows),
        f"hmm_leave_one_{by}_out",
        corpus_source(sequences),
        by=by,
        seed=seed,
        **training_parameters(config, features),
    )


def original_scores(source: DataSource, n_mix: int = 3, include_garbage: bool = False) -> pd.DataFrame:
    """The original 2013 models on the five original test segments (features = logged values / 1000).

    One row per segment: recording, start, end (1-based inclusive), n_frames, loglik_<a>, p_hmm_<a>,
    and winner (the action of highest likelihood), for a = grasp, tap, touch (the push model).
    """
    mat = source.original_hmms(n_mix)
    if mat is None:
        raise DataError(f"the data source has no original HMMs with M = {n_mix} ({source.describe()})")
    rec = load_original_models(mat, include_garbage=include_garbage)
    rows = []
    for seq in original_test_segments(source):
        row = _predict_rows(rec, [seq])[0]
        row["winner"] = row.pop("predicted")
        del row["converged"]
        rows.append(row)
    return tidy(
        pd.DataFrame(rows),
        "hmm_original_scores",
        source.describe(),
        n_mix=n_mix,
        include_garbage=include_garbage,
    )


def segmentation_table(segmentations: Sequence[tuple[Any, list[Any]]], data_source: str) -> pd.DataFrame:
    """One row per segment found: recording, action, segment number, start, end, n_frames, tracking events.

    ``segmentations`` as :func:`glu.gestures.corpus.recording_segmentations` returns them.
    """
    rows = []
    for seg, ref in segmentations:
        kinds = pd.Series([e.kind for e in seg.events], dtype=object).value_counts().to_dict()
        for i, s in enumerate(seg.segments, 1):
            rows.append(
                {
                    "recording": seg.recording,
                    "action": s.label,
                    "segment": i,
                    "start": s.start,
                    "end": s.end,
                    "n_frames": s.n_frames,
                    "n_reference": len(ref),
                    "n_gaps": kinds.get("gap", 0),
                    "n_spikes": kinds.get("spike", 0),
                    "n_jumps": kinds.get("jump", 0),
                }
            )
        if not seg.segments:
            rows.append({"recording": seg.recording, "action": None, "segment": 0, "n_reference": len(ref)})
    return tidy(pd.DataFrame(rows), "gesture_segmentation", data_source)


def train_on(
    sequences: Sequence[LabelledSequence],
    config: TrainingConfig | None = None,
    seed: int = 0,
    features: Features = None,
) -> Recognizer:
    """A recogniser of one HMM per action present in ``sequences``, trained with ``config`` on
    ``features``."""
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    meta = {"data": corpus_source(sequences)}
    return train_recognizer(
        _by_action(sequences, actions), config, seed=seed, features=features, meta=meta, warn=False
    )


def anticipation_banks(
    source: DataSource,
    config: TrainingConfig | None = None,
    n_per_action: int = 20,
    seed: int = 0,
    features: Features = None,
) -> dict[str, Recognizer]:
    """The banks of HMMs notebook 08 anticipates with, by name: ``original``, the originals' 2013 HMMs (when
    the data has them); ``glu`` and ``mixsplit``, trained with ``config`` by glu's recipe and by the
    originals' (``recipe="mixsplit"``) on ``features`` of the standing recordings only — never on the two
    seated taps the anticipation shows (synthetic data: ``n_per_action`` gestures per action)."""
    banks = {}
    mat = source.original_hmms()
    if mat is not None:
        banks["original"] = load_original_models(mat)
    config = config or TrainingConfig()
    sequences = gesture_sequences(source, n_per_action=n_per_action, seed=seed, include_test=False)
    banks["glu"] = train_on(sequences, config, seed=seed, features=features)
    banks["mixsplit"] = train_on(sequences, config.replace(recipe="mixsplit"), seed=seed, features=features)
    return banks


def training_table(recognizer: Recognizer) -> pd.DataFrame:
    """How training went, one row per action: sequences, frames, EM iterations, convergence,
    log-likelihood."""
    rows = []
    for a, r in recognizer.reports.items():
        rows.append(
            {
                "action": a,
                "n_sequences": r.n_sequences,
                "n_frames": r.n_frames,
                "em_iterations": r.n_iter,
                "max_iterations": r.max_iter,
                "converged": r.converged,
                "loglik_per_frame": r.final_loglik / max(r.n_frames, 1),
            }
        )
    return tidy(
        pd.DataFrame(rows), "hmm_training", model_source(recognizer), **recognizer_settings(recognizer)
    )


def recognizer_settings(recognizer: Recognizer) -> dict[str, Any]:
    """The training settings of a recogniser (recipe, Q, M, EM limits: its ``config``), with the seed and
    features its ``meta`` records."""
    config = recognizer.config
    keys = ("recipe", "n_states", "n_mix", "n_iter", "tol", "covar_reg")
    settings = {} if config is None else {k: getattr(config, k) for k in keys}
    return {**settings, **{k: recognizer.meta[k] for k in ("seed", "features") if k in recognizer.meta}}
