"""Evaluation of gesture recognition: cross-validation on synthetic gestures, real recordings, original models.

Every function returns a tidy pandas DataFrame (one row per test sequence, or per condition), so numbers
quoted anywhere are computed, never typed:

* :func:`synthetic_corpus` — labelled feature sequences from :mod:`glu.data.synthetic_gestures`;
* :func:`cross_validate` — stratified k-fold: train a recogniser on k-1 folds, classify the held-out fold;
  :func:`confusion_matrix` and :func:`accuracy` summarise the predictions;
* :func:`accuracy_vs_noise` — k-fold accuracy as the sensor noise grows;
* :func:`leave_one_out` — on the real segments, hold out one recording (or one segment) at a time;
* :func:`original_scores` — the original 2013 models on the five original test segments.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from glu.data.source import DataSource
from glu.errors import DataError
from glu.hmm import ACTIONS, Recognizer, load_original_models, train_recognizer
from glu.segmentation import ORIGINAL_SEGMENTS, RECORDING_ACTION, LabelledSequence

TRAIN_DEFAULTS: dict[str, Any] = {"n_states": 6, "n_mix": 3, "n_iter": 200, "tol": 1e-4, "covar_reg": 1e-3}
"""Training settings used when none are given (those of :func:`glu.hmm.train_hmm`)."""


def synthetic_corpus(
    n_per_action: int,
    seed: int = 0,
    *,
    actions: tuple[str, ...] = ACTIONS,
    noise: float = 0.01,
    spike_rate: float = 0.005,
    dropout_rate: float = 0.2,
) -> list[LabelledSequence]:
    """``n_per_action`` synthetic gestures per action, as repaired feature sequences (see :mod:`glu.data.synthetic_gestures`)."""
    from glu.data.synthetic_gestures import synthesize_gestures

    gestures = synthesize_gestures(
        n_per_action * len(actions), seed, actions=actions,
        noise=noise, spike_rate=spike_rate, dropout_rate=dropout_rate,
    )  # fmt: skip
    return [
        LabelledSequence(g.action, g.features(), f"synthetic-{i}", 1, len(g.t))
        for i, g in enumerate(gestures)
    ]


def stratified_folds(labels: Sequence[str], k: int, seed: int = 0) -> np.ndarray:
    """Fold number (0 … k-1) of each item, shape (n,): each label's items shuffled (seeded), dealt in turn."""
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


def _train(
    seqs: Sequence[LabelledSequence], actions: Sequence[str], seed: int, train: dict[str, Any]
) -> Recognizer:
    by_action = {a: [s.xyz for s in seqs if s.action == a] for a in actions}
    by_action = {a: v for a, v in by_action.items() if v}
    return train_recognizer(by_action, seed=seed, warn=False, **{**TRAIN_DEFAULTS, **train})


def _predict_rows(rec: Recognizer, test: Sequence[LabelledSequence], **extra: Any) -> list[dict[str, Any]]:
    rows = []
    for s in test:
        ll = rec.loglik(s.xyz)
        p = np.exp(ll - ll.max())
        p /= p.sum()
        row = {
            **extra, "recording": s.recording, "start": s.start, "end": s.end, "n_frames": len(s.xyz),
            "action": s.action, "predicted": rec.actions[int(np.argmax(ll))],
        }  # fmt: skip
        row.update({f"loglik_{a}": float(v) for a, v in zip(rec.actions, ll, strict=True)})
        row.update({f"p_hmm_{a}": float(v) for a, v in zip(rec.actions, p, strict=True)})
        row["correct"] = row["predicted"] == s.action
        row["converged"] = all(r.converged for r in rec.reports.values())
        rows.append(row)
    return rows


def cross_validate(
    sequences: Sequence[LabelledSequence], k: int = 5, seed: int = 0, **train: Any
) -> pd.DataFrame:
    """Stratified k-fold cross-validation: one row per sequence with its fold, prediction and scores.

    ``train`` overrides :data:`TRAIN_DEFAULTS` (``n_states``, ``n_mix``, ``n_iter``, ``tol``, ``covar_reg``).
    Columns: fold, recording, start, end, n_frames, action, predicted, loglik_<a>, p_hmm_<a>, correct, converged.
    """
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    folds = stratified_folds([s.action for s in sequences], k, seed)
    rows = []
    for f in range(k):
        tr = [s for s, g in zip(sequences, folds, strict=True) if g != f]
        te = [s for s, g in zip(sequences, folds, strict=True) if g == f]
        rows += _predict_rows(_train(tr, actions, seed, train), te, fold=f)
    return pd.DataFrame(rows)


def confusion_matrix(predictions: pd.DataFrame, actions: Sequence[str] | None = None) -> pd.DataFrame:
    """Counts of (true action, predicted action): rows ``action``, columns ``predicted``."""
    actions = list(actions) if actions is not None else list(dict.fromkeys(predictions["action"]))
    cm = pd.crosstab(
        pd.Categorical(predictions["action"], categories=actions),
        pd.Categorical(predictions["predicted"], categories=actions),
        rownames=["action"], colnames=["predicted"], dropna=False,
    )  # fmt: skip
    return cm


def accuracy(predictions: pd.DataFrame) -> float:
    """The fraction of correct predictions (NaN if there are none)."""
    return float(predictions["correct"].mean()) if len(predictions) else float("nan")


def accuracy_vs_noise(
    noise_levels: Sequence[float] = (0.0, 0.01, 0.02, 0.04, 0.08),
    n_per_action: int = 20,
    k: int = 5,
    seed: int = 0,
    actions: tuple[str, ...] = ACTIONS,
    **train: Any,
) -> pd.DataFrame:
    """k-fold accuracy on synthetic corpora with growing sensor noise (metres, std on every joint).

    One row per noise level: noise_m, n_sequences, k, accuracy, and accuracy_<action> per action.
    The corpora share the seed, so only the noise differs between rows.
    """
    rows = []
    for noise in noise_levels:
        pred = cross_validate(
            synthetic_corpus(n_per_action, seed, actions=actions, noise=noise), k, seed, **train
        )
        row = {"noise_m": float(noise), "n_sequences": len(pred), "k": k, "accuracy": accuracy(pred)}
        for a in actions:
            row[f"accuracy_{a}"] = accuracy(pred[pred["action"] == a])
        row["all_converged"] = bool(pred["converged"].all())
        rows.append(row)
    return pd.DataFrame(rows)


def leave_one_out(
    sequences: Sequence[LabelledSequence], by: str = "recording", seed: int = 0, **train: Any
) -> pd.DataFrame:
    """Hold out one recording (``by="recording"``) or one segment (``by="segment"``) at a time.

    Models are trained on everything else. A held-out sequence whose action has no training sequence
    left cannot be recognised; it is reported with ``testable = False`` and ``predicted`` None rather
    than counted as an error. Columns as :func:`cross_validate`, plus held_out and testable.
    """
    if by not in ("recording", "segment"):
        raise DataError(f"by={by!r}; allowed: 'recording', 'segment'")
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    keys = [
        s.recording if by == "recording" else f"{s.recording}:{s.start}-{s.end}#{i}"
        for i, s in enumerate(sequences)
    ]
    rows = []
    for key in dict.fromkeys(keys):
        te = [s for s, g in zip(sequences, keys, strict=True) if g == key]
        tr = [s for s, g in zip(sequences, keys, strict=True) if g != key]
        trained_actions = {s.action for s in tr}
        testable = [s for s in te if s.action in trained_actions]
        if testable:
            rows += _predict_rows(_train(tr, actions, seed, train), testable, held_out=key, testable=True)
        for s in te:
            if s.action not in trained_actions:
                rows.append({
                    "held_out": key, "testable": False, "recording": s.recording, "start": s.start, "end": s.end,
                    "n_frames": len(s.xyz), "action": s.action, "predicted": None, "correct": False,
                })  # fmt: skip
    return pd.DataFrame(rows)


def original_scores(root: str | os.PathLike, n_mix: int = 3, include_garbage: bool = False) -> pd.DataFrame:
    """The original 2013 models on the five original test segments (features = logged values / 1000).

    One row per segment: recording, start, end (1-based inclusive), n_frames, loglik_<a>, p_hmm_<a>,
    and winner (the action of highest likelihood), for a = grasp, tap, touch (the push model).
    """
    from glu.features import load_features
    from glu.hmm import ORIGINAL_MODEL_FILES

    root = Path(root)
    if n_mix not in ORIGINAL_MODEL_FILES:
        raise DataError(f"n_mix={n_mix}; the originals have models with M in {sorted(ORIGINAL_MODEL_FILES)}")
    rec = load_original_models(root / ORIGINAL_MODEL_FILES[n_mix], include_garbage=include_garbage)
    rows = []
    for name, ranges in ORIGINAL_SEGMENTS.items():
        traj = load_features(root / "gestures" / name / "data.log", policy=None).pieces[0]
        for a, b in ranges:
            seq = LabelledSequence(RECORDING_ACTION[name], traj.frames(a, b).xyz, name, a, b)
            row = _predict_rows(rec, [seq])[0]
            row["winner"] = row.pop("predicted")
            del row["converged"]
            rows.append(row)
    return pd.DataFrame(rows)


def gesture_sequences(
    source: DataSource,
    n_per_action: int = 20,
    seed: int = 0,
    actions: Sequence[str] = ACTIONS,
    include_test: bool = True,
) -> list[LabelledSequence]:
    """Labelled training sequences of a data source: the real segments, or a seeded synthetic corpus.

    With real gesture recordings, the repetitions found by automatic segmentation of the training
    recordings plus, with ``include_test``, the originals' hand-cut segments of the two single-tap
    recordings (leave them out when those recordings are the test data, as in effect anticipation);
    restricted to ``actions``. Otherwise ``n_per_action`` synthetic gestures per action.
    """
    from glu.segmentation import real_segments

    if source.root is not None and source.optional("gestures"):
        return [s for s in real_segments(source.root, include_original=include_test) if s.action in actions]
    return synthetic_corpus(n_per_action, seed, actions=tuple(actions))


def recording_segmentations(source: DataSource, seed: int = 0) -> list[tuple[Any, list[Any]]]:
    """Automatic segmentation of every recording, each with its reference segments.

    Real data: the six logs, with the originals' hand-cut segments as reference. Synthetic data: one
    continuous synthetic recording per action (four repetitions each), with the true repetitions.
    Returns a list of (:class:`~glu.segmentation.RecordingSegmentation`, reference segments).
    """
    from glu.segmentation import (
        RecordingSegmentation,
        Segment,
        original_segments,
        segment_recording,
        segment_repetitions,
    )

    if source.root is not None and source.optional("gestures"):
        names = sorted(RECORDING_ACTION, key=list(RECORDING_ACTION).index)
        return [
            (segment_recording(source.file(f"gestures/{n}/data.log")), original_segments(n))
            for n in names if source.optional(f"gestures/{n}/data.log")
        ]  # fmt: skip
    from glu.data.synthetic_gestures import synthesize_recording
    from glu.trajectories import repair

    out = []
    for action in ("grasp", "tap", "touch", "push"):
        g = synthesize_recording(action, 4, seed)
        repaired = repair(g.trajectory())
        name = f"synthetic {action}"
        pieces = [segment_repetitions(tr, action, recording=name) for tr in repaired.pieces if len(tr) >= 2]
        ref = [Segment(a, b, action, name) for a, b in g.segments]
        out.append((RecordingSegmentation(name, pieces, repaired.events), ref))
    return out


def segmentation_table(segmentations: Sequence[tuple[Any, list[Any]]]) -> pd.DataFrame:
    """One row per segment found: recording, action, segment number, start, end, n_frames, tracking events."""
    rows = []
    for seg, ref in segmentations:
        kinds = pd.Series([e.kind for e in seg.events], dtype=object).value_counts().to_dict()
        for i, s in enumerate(seg.segments, 1):
            rows.append({
                "recording": seg.recording, "action": s.label, "segment": i, "start": s.start, "end": s.end,
                "n_frames": s.n_frames, "n_reference": len(ref), "n_gaps": kinds.get("gap", 0),
                "n_spikes": kinds.get("spike", 0), "n_jumps": kinds.get("jump", 0),
            })  # fmt: skip
        if not seg.segments:
            rows.append({"recording": seg.recording, "action": None, "segment": 0, "n_reference": len(ref)})
    return pd.DataFrame(rows)


def train_on(sequences: Sequence[LabelledSequence], seed: int = 0, **train: Any) -> Recognizer:
    """Train one HMM per action present in ``sequences`` (settings: :data:`TRAIN_DEFAULTS` overridden by ``train``)."""
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    return _train(sequences, actions, seed, train)


def training_table(recognizer: Recognizer) -> pd.DataFrame:
    """How training went, one row per action: sequences, frames, EM iterations, convergence, log-likelihood."""
    rows = []
    for a, r in recognizer.reports.items():
        rows.append({
            "action": a, "n_sequences": r.n_sequences, "n_frames": r.n_frames, "em_iterations": r.n_iter,
            "max_iterations": r.max_iter, "converged": r.converged, "loglik_per_frame": r.final_loglik / max(r.n_frames, 1),
        })  # fmt: skip
    return pd.DataFrame(rows)


def test_segments(source: DataSource, seed: int = 0, n_per_action: int = 2) -> list[LabelledSequence]:
    """Gestures to recognise in the fusion experiments: the originals' five tap segments, as logged, or
    ``n_per_action`` fresh synthetic gestures per action (seeded apart from the training corpus)."""
    from glu.features import load_features

    if source.root is not None and source.optional("gestures"):
        out = []
        for name, ranges in ORIGINAL_SEGMENTS.items():
            traj = load_features(source.file(f"gestures/{name}/data.log"), policy=None).pieces[0]
            out += [
                LabelledSequence(RECORDING_ACTION[name], traj.frames(a, b).xyz, name, a, b) for a, b in ranges
            ]
        return out
    corpus = synthetic_corpus(n_per_action, seed + 1000)
    return [s._replace(recording=f"synthetic {s.action} {i}") for i, s in enumerate(corpus)]
