"""The real data's correspondence test, done so that it can fail: nested cross-validation on the standing
segments, then the seated taps with their typicality.

The published logs hold 11 standing repetitions of one person (grasp, tap, touch) and two seated taps
(the anticipation experiment's). The feature set (raw or start-centred, :mod:`glu.gestures.invariants`)
and the strength of the HMMs' covariance prior (``covar_reg``) were first chosen with the seated taps in
view, and the same leave-one-segment-out that tuned them reported the accuracy. Here:

* **Nested cross-validation** (:func:`nested_cv`). Each standing segment is held out in turn (the outer
  fold); on the other ten, every candidate (feature set × training setting) is scored by an inner
  leave-one-segment-out, the best is chosen (ties to the first candidate in the order given), trained on
  the ten, and recognises the held-out segment. The outer accuracy, k of n, gets an exact
  (Clopper–Pearson) interval. Nothing outside the standing data chooses anything.
* **What tuning on the same data would report**: every candidate's plain leave-one-segment-out accuracy on
  all the standing segments, and the best of them.
* **The seated taps** (:func:`seated_report`): the candidate chosen by leave-one-segment-out on all the
  standing segments, trained on all of them, recognises each seated tap. Beside its posterior: how
  typical the tap is for the model that wins (its per-frame log-likelihood against the range of the
  training sequences, :mod:`glu.gestures.typicality`), the first frame at which tap leads, the frame from
  which tap leads to the end, and the frame at which the hand starts to move (its distance from the first
  frame exceeds :data:`ONSET_SHARE` of its largest). The data hold no seated grasp or touch, so a
  recogniser that always answers "tap" also gets both right: the **always-tap** baseline is reported
  beside every accuracy.

Each action's model depends only on that action's segments, so every model the nested scheme needs is
"action a trained without the segments E" (E at most two of a's segments), for each candidate and seed: a
few dozen small models per candidate, trained in one batch (:func:`glu.hmm.train`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.gestures.corpus import LabelledSequence
from glu.gestures.invariants import Invariants
from glu.gestures.typicality import training_range
from glu.hmm import BatchScorer, TrainingConfig, loglik_many, stack_models, train
from glu.stats import clopper_pearson
from glu.studies.correspondence.seated import parse_setting
from glu.tidy import corpus_source, tidy

FEATURES: tuple[str, ...] = ("raw", "centred")
"""The feature sets chosen among by default."""
SETTINGS: tuple[str, ...] = ("reg0.003", "reg0.03", "reg0.3")
"""The training settings chosen among by default: the covariance prior a decade either side of glu's."""
ONSET_SHARE = 0.1
"""The hand has started to move when its distance from the first frame exceeds this share of its largest."""


class Candidate(NamedTuple):
    """A feature set and a training setting (a label of
    :func:`glu.studies.correspondence.seated.parse_setting`)."""

    features: str
    setting: str

    @property
    def label(self) -> str:
        """``"features, setting"``, as tables and figures name the candidate."""
        return f"{self.features}, {self.setting}"


class NestedCV(NamedTuple):
    """What :func:`nested_cv` returns (each a tidy frame).

    Attributes
    ----------
    folds : one row per seed and outer fold: seed, recording, start, end, action, chosen, inner_accuracy,
        predicted, correct
    summary : one row per seed: correct, testable, accuracy, ci_low, ci_high (Clopper–Pearson), always_tap
        (the always-tap baseline's accuracy), tuned_accuracy and tuned_candidate (the best plain
        leave-one-segment-out on all the standing segments: what tuning on the reported data gives)
    candidates : one row per seed and candidate: features, setting, loso_accuracy (plain, on all the
        standing segments)
    """

    folds: pd.DataFrame
    summary: pd.DataFrame
    candidates: pd.DataFrame


def _candidates(features: Sequence[str], settings: Sequence[str]) -> list[Candidate]:
    return [Candidate(Invariants.parse(f).name, s) for f in features for s in settings]


def _models(
    xs: dict[str, list[np.ndarray]],
    by_action: Mapping[str, list[int]],
    candidates: Sequence[Candidate],
    seeds: Sequence[int],
    config: TrainingConfig,
) -> dict[tuple, Any]:
    """Every model the nested scheme needs: (candidate, seed, action, left-out segments) → GestureHMM.

    One batch per training setting; settings without random initialisation (mixsplit) train once for
    every seed.
    """
    models: dict[tuple, Any] = {}
    for setting in dict.fromkeys(c.setting for c in candidates):
        s = parse_setting(setting)
        cfg = config.replace(**s)
        run_seeds = [-1] if cfg.recipe == "mixsplit" else list(seeds)
        jobs, job_seeds = {}, {}
        for c in (c for c in candidates if c.setting == setting):
            for seed in run_seeds:
                for a, idx in by_action.items():
                    for r in range(3):
                        for out in combinations(idx, r):
                            rest = [xs[c.features][i] for i in idx if i not in out]
                            if rest:
                                key = (c, seed, a, frozenset(out))
                                jobs[key], job_seeds[key] = rest, max(seed, 0)
        for key, (model, _) in train(jobs, cfg, seed=job_seeds, warn=False).items():
            c, seed, a, out = key
            for sd in seeds if seed == -1 else (seed,):
                models[(c, sd, a, out)] = model
    return models


def nested_cv(
    standing: Sequence[LabelledSequence],
    features: Sequence[str] = FEATURES,
    settings: Sequence[str] = SETTINGS,
    seeds: Sequence[int] = (0, 1, 2),
    config: TrainingConfig | None = None,
) -> NestedCV:
    """Nested leave-one-segment-out over ``standing`` (see the module docstring), for each EM seed.

    Parameters
    ----------
    standing : the labelled standing segments
    features, settings : the candidates, every feature set with every training setting, in this order
        (ties go to the first)
    seeds : EM seeds (one nested cross-validation each)
    config : the training settings the candidates leave as they are (default glu's)
    """
    config = config or TrainingConfig()
    cands = _candidates(features, settings)
    actions = tuple(dict.fromkeys(s.action for s in standing))
    by_action = {a: [i for i, s in enumerate(standing) if s.action == a] for a in actions}
    xs = {c.features: [Invariants.parse(c.features).transform(s.xyz) for s in standing] for c in cands}
    score = _Scorer(
        _models(xs, by_action, cands, seeds, config), xs, by_action, actions, [s.action for s in standing]
    )
    folds, summary, cand_rows = [], [], []
    everyone = list(range(len(standing)))
    for seed in seeds:
        plain = {c: score.loso(c, seed, everyone, set()) for c in cands}
        cand_rows += [
            {"seed": seed, "features": c.features, "setting": c.setting, "loso_accuracy": plain[c]}
            for c in cands
        ]
        tested = []
        for i, s in enumerate(standing):
            if score.predict(cands[0], seed, i, {i}) is None:
                continue  # its action has no other segment: not testable
            rest = [j for j in everyone if j != i]
            inner = {c: score.loso(c, seed, rest, {i}) for c in cands}
            chosen = _best(cands, inner)
            predicted = score.predict(chosen, seed, i, {i})
            tested.append(
                {
                    "seed": seed,
                    "recording": s.recording,
                    "start": s.start,
                    "end": s.end,
                    "action": s.action,
                    "chosen": chosen.label,
                    "inner_accuracy": inner[chosen],
                    "predicted": predicted,
                    "correct": predicted == s.action,
                }
            )
        folds += tested
        summary.append(_seed_summary(seed, tested, plain, _best(cands, plain)))
    params = {
        "features": list(features),
        "settings": list(settings),
        "seeds": list(seeds),
        "n_segments": len(standing),
    }
    source = corpus_source(standing)
    return NestedCV(
        tidy(pd.DataFrame(folds), "correspondence_nested_folds", source, **params),
        tidy(pd.DataFrame(summary), "correspondence_nested_cv", source, **params),
        tidy(pd.DataFrame(cand_rows), "correspondence_candidates", source, **params),
    )


def _best(cands: Sequence[Candidate], accuracy: Mapping[Candidate, float]) -> Candidate:
    """The candidate of highest accuracy (NaN lowest; ties go to the first)."""
    return max(cands, key=lambda c: (np.nan_to_num(accuracy[c], nan=-1.0), -cands.index(c)))


def _seed_summary(seed: int, tested: list[dict], plain: Mapping[Candidate, float], best: Candidate) -> dict:
    """One seed's nested accuracy with its exact interval, beside always-tap and the tuned-on-test best."""
    k, n = sum(bool(f["correct"]) for f in tested), len(tested)
    lo, hi = clopper_pearson(k, n)
    return {
        "seed": seed,
        "correct": k,
        "testable": n,
        "accuracy": k / n,
        "ci_low": lo,
        "ci_high": hi,
        "always_tap": float(np.mean([f["action"] == "tap" for f in tested])),
        "tuned_accuracy": plain[best],
        "tuned_candidate": best.label,
        "recordings": len({f["recording"] for f in tested}),
    }


@dataclass(frozen=True)
class _Scorer:
    """Predictions of each candidate's recogniser trained without some segments (the models trained once)."""

    models: Mapping
    xs: Mapping[str, list[np.ndarray]]
    by_action: Mapping[str, list[int]]
    actions: tuple[str, ...]
    labels: list[str]

    def predict(self, c: Candidate, seed: int, i: int, without: set[int]) -> str | None:
        """Segment ``i``'s action by ``c``'s recogniser trained without ``without`` (None: an action has no
        segment left to train on)."""
        bank = [
            self.models.get((c, seed, a, frozenset(without & set(self.by_action[a])))) for a in self.actions
        ]
        if any(m is None for m in bank):
            return None
        return self.actions[int(np.argmax(loglik_many(stack_models(bank), [self.xs[c.features][i]])[0]))]

    def loso(self, c: Candidate, seed: int, pool: Sequence[int], also_without: set[int]) -> float:
        """Leave-one-segment-out accuracy of ``c`` over ``pool``, each also without ``also_without``."""
        hits = [self.predict(c, seed, j, {j} | also_without) for j in pool]
        ok = [h == self.labels[j] for h, j in zip(hits, pool, strict=True) if h is not None]
        return float(np.mean(ok)) if ok else float("nan")


def onset_frame(xyz: np.ndarray, share: float = ONSET_SHARE) -> int:
    """The first frame (1-based) at which the hand's distance from the first frame exceeds ``share`` of its
    largest distance; ``xyz``, shape (n_frames, 3), the hand's path (any unit: only ratios are read)."""
    d = np.linalg.norm(np.asarray(xyz) - xyz[0], axis=1)
    return int(np.argmax(d > share * d.max())) + 1 if d.max() > 0 else 1


def seated_report(
    standing: Sequence[LabelledSequence],
    seated: Sequence[LabelledSequence],
    cv: NestedCV,
    config: TrainingConfig | None = None,
) -> pd.DataFrame:
    """The seated taps, recognised by the candidate leave-one-segment-out chooses on all the standing
    segments (per seed), trained on all of them; with their typicality and when tap leads.

    Returns
    -------
    One row per seed and seated tap: seed, recording, candidate, predicted, p_tap (the likelihood
    reading), per_frame (log-likelihood per frame under the winning model), training_low, training_high
    (the range of the training sequences' per-frame log-likelihoods under that model), below
    (training_low − per_frame: nats per frame below every training sequence), tap_first (the first frame at
    which tap leads), tap_from (the frame from which tap leads to the end), onset (the frame the hand
    starts to move), n_frames, always_tap (whether the always-tap baseline is right: every seated tap is
    a tap).
    """
    config = config or TrainingConfig()
    rows = []
    actions = tuple(dict.fromkeys(s.action for s in standing))
    for r in cv.summary.itertuples():
        features, setting = r.tuned_candidate.split(", ", 1)
        inv = Invariants.parse(features)
        cfg = config.replace(**parse_setting(setting))
        sets = {a: [inv.transform(s.xyz) for s in standing if s.action == a] for a in actions}
        trained = train(sets, cfg, seed=int(r.seed), warn=False)
        models = [trained[a][0] for a in actions]
        bank = stack_models(models)
        for s in seated:
            x = inv.transform(s.xyz)
            curves = BatchScorer(models).loglik_curves([x])[0]  # (T, A): log L(G_1^t | a)
            ll = loglik_many(bank, [x])[0]
            k = int(np.argmax(ll))
            p = np.exp(ll - ll.max())
            p /= p.sum()
            rng = training_range(models[k], sets[actions[k]])
            leads = np.argmax(curves, axis=1) == actions.index("tap")
            tail = np.flatnonzero(~leads)
            rows.append(
                {
                    "seed": int(r.seed),
                    "recording": s.recording,
                    "candidate": r.tuned_candidate,
                    "predicted": actions[k],
                    "p_tap": float(p[actions.index("tap")]),
                    "per_frame": float(ll[k] / len(x)),
                    "training_low": rng.low,
                    "training_high": rng.high,
                    "below": rng.low - float(ll[k] / len(x)),
                    "tap_first": int(np.argmax(leads)) + 1 if leads.any() else None,
                    "tap_from": (int(tail[-1]) + 2 if len(tail) else 1) if leads[-1] else None,
                    "onset": onset_frame(s.xyz),
                    "n_frames": len(x),
                    "always_tap": s.action == "tap",
                }
            )
    return tidy(
        pd.DataFrame(rows),
        "seated_typicality",
        corpus_source(standing),
        seated=[s.recording for s in seated],
        onset_share=ONSET_SHARE,
    )
