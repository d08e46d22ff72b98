"""How trustworthy is p_HMM on real gestures? Its three readings on held-out real segments.

The fusion rules take ``p_HMM(A | G)`` as a probability. :func:`segment_readings` measures whether it
is one on the real standing segments, leaving each segment out in turn (trained on the others, glu's
recipe): for each held-out segment, ``p_HMM`` read from the likelihoods (as the originals), per frame, and
calibrated (:mod:`glu.gestures.calibration`) with an inverse temperature fitted on the *other* segments
only — each of them scored by models that saw neither it nor the held-out segment (a nested leave-one-out),
so no segment's own label ever tunes its calibration.

Each action's model depends only on that action's segments, so every model the nested scheme needs is
"action a without the segments E", with E at most two of a's segments: a few dozen small models in one
batch (:func:`glu.hmm.train`), however many folds use them.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import combinations

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.gestures.calibration import READINGS, fit_temperature, p_hmm_reading
from glu.gestures.corpus import LabelledSequence
from glu.gestures.invariants import Invariants
from glu.hmm import GestureHMM, TrainingConfig, loglik_many, stack_models, train
from glu.tidy import corpus_source, tidy, training_parameters


def segment_readings(
    sequences: Sequence[LabelledSequence],
    config: TrainingConfig | None = None,
    seed: int = 0,
    features: str = "raw",
) -> pd.DataFrame:
    """Each real segment, left out, recognised by models trained on the others: p_HMM under every reading.

    Parameters
    ----------
    sequences : labelled segments (the real standing repetitions); an action needs at least three
        segments for its held-out ones to be scored (two for training the inner folds)
    config : the HMMs' training settings (default glu's)
    seed : EM seed of every model
    features : the invariant features the models see (:class:`~glu.gestures.invariants.Invariants` name)

    Returns
    -------
    One row per (segment, reading): recording, start, end, action, reading, predicted, p_true (the
    probability given to the true action), confidence (that of the predicted one), correct, beta (the
    calibrated reading's inverse temperature; 1 for the likelihood, NaN per frame), n_frames.
    """
    config = config or TrainingConfig()
    inv = Invariants.parse(features)
    xs = [s.xyz if inv.is_raw else inv.transform(s.xyz) for s in sequences]
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    by_action = {a: [i for i, s in enumerate(sequences) if s.action == a] for a in actions}
    models = _models_without(xs, by_action, config, seed)

    def loglik(i: int, without: set[int]) -> np.ndarray:
        """``log L(segment i | a)`` under each action's model trained without the segments ``without``, shape
        (n_actions,) in ``actions`` order; all NaN when one of those models is missing."""
        bank = [models.get((a, frozenset(without & set(by_action[a])))) for a in actions]
        if any(m is None for m in bank):
            return np.full(len(actions), np.nan)
        return loglik_many(stack_models(bank), [xs[i]])[0]

    labels = np.array([actions.index(s.action) for s in sequences])
    rows = []
    for i, s in enumerate(sequences):
        ll = loglik(i, {i})
        others = [j for j in range(len(sequences)) if j != i] if np.isfinite(ll).all() else []
        inner = [(j, v) for j in others if np.isfinite(v := loglik(j, {i, j})).all()]
        if not inner:
            continue  # no model of its action without it, or no other segment scored without both
        beta = fit_temperature(np.array([v for _, v in inner]), labels[[j for j, _ in inner]])
        t = np.array(len(xs[i]))
        for reading in READINGS:
            p = p_hmm_reading(ll, t, reading, beta)
            k = int(np.argmax(p))
            rows.append(
                {
                    "recording": s.recording,
                    "start": s.start,
                    "end": s.end,
                    "action": s.action,
                    "reading": reading,
                    "predicted": actions[k],
                    "p_true": float(p[labels[i]]),
                    "confidence": float(p[k]),
                    "correct": bool(k == labels[i]),
                    "beta": {"likelihood": 1.0, "per-frame": np.nan}.get(reading, beta),
                    "n_frames": len(xs[i]),
                }
            )
    if not rows:
        raise DataError(
            "no segment can be scored (segments per action: "
            + ", ".join(f"{a} {len(i)}" for a, i in by_action.items())
            + "): a held-out segment needs models of every action trained without it and one more segment"
        )
    return tidy(
        pd.DataFrame(rows),
        "p_hmm_real_segments",
        corpus_source(sequences),
        seed=seed,
        features=inv.name,
        **training_parameters(config),
    )


def _models_without(
    xs: list[np.ndarray], by_action: dict[str, list[int]], config: TrainingConfig, seed: int
) -> dict[tuple[str, frozenset[int]], GestureHMM]:
    """Every model the nested leave-one-out needs, in one batch: action a without E, E at most two of a's
    segments (none when they would leave it nothing to train on)."""
    jobs = {}
    for a, idx in by_action.items():
        for r in range(3):
            for left_out in combinations(idx, r):
                rest = [xs[i] for i in idx if i not in left_out]
                if rest:
                    jobs[(a, frozenset(left_out))] = rest
    return {k: m for k, (m, _) in train(jobs, config, seed=seed, warn=False).items()}


def segment_calibration(readings: pd.DataFrame, bins: int = 5) -> pd.DataFrame:
    """Per reading of :func:`segment_readings`: accuracy, mean confidence, expected calibration error (top
    label, ``bins`` equal-width bins), log-loss, and how many segments got p ≥ 0.99.

    Columns: reading, segments, accuracy, confidence, ece, log_loss, certain.
    """
    rows = []
    for reading, g in readings.groupby("reading", sort=False):
        conf, ok = g["confidence"].to_numpy(), g["correct"].to_numpy(dtype=float)
        b = np.minimum((conf * bins).astype(int), bins - 1)
        ece = sum(abs(ok[b == k].sum() - conf[b == k].sum()) for k in range(bins)) / len(g)
        rows.append(
            {
                "reading": reading,
                "segments": len(g),
                "accuracy": ok.mean(),
                "confidence": conf.mean(),
                "ece": ece,
                "log_loss": float(-np.log(np.maximum(g["p_true"].to_numpy(), 1e-6)).mean()) + 0.0,
                "certain": int((conf >= 0.99).sum()),
            }
        )
    return tidy(
        pd.DataFrame(rows),
        "p_hmm_real_calibration",
        readings.attrs.get("data_source", ""),
        bins=bins,
        **readings.attrs.get("parameters", {}),
    )
