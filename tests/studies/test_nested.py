"""Nested cross-validation on the real data's standing segments, and the seated taps' report, against a
brute-force reference that trains every model of every fold on its own."""

from __future__ import annotations

import numpy as np
import pytest

from glu.gestures.corpus import synthetic_corpus
from glu.gestures.invariants import Invariants
from glu.hmm import TrainingConfig, loglik_many, stack_models, train
from glu.stats import clopper_pearson
from glu.studies.correspondence import nested
from glu.studies.correspondence.seated import parse_setting

CONFIG = TrainingConfig(n_states=2, n_mix=1, n_iter=3)
FEATURES, SETTINGS = ("raw", "centred"), ("reg0.01", "reg1")
ACTIONS = ("grasp", "tap")


@pytest.fixture(scope="module")
def segments():
    return list(synthetic_corpus(3, seed=8, noise=0.05, actions=ACTIONS))


@pytest.fixture(scope="module")
def cv(segments):
    return nested.nested_cv(segments, FEATURES, SETTINGS, seeds=(0,), config=CONFIG)


MODELS: dict = {}


def brute_predict(segments, features, setting, seed, i, without):
    """Train each action's model on its segments minus ``without``, alone, and name segment i."""
    inv = Invariants.parse(features)
    key = (features, setting, seed, frozenset(without))
    if key not in MODELS:  # a fold's models, each trained on its own (not in a batch)
        cfg = CONFIG.replace(**parse_setting(setting))
        MODELS[key] = [
            train(
                [inv.transform(s.xyz) for j, s in enumerate(segments) if s.action == a and j not in without],
                cfg,
                seed=seed,
                warn=False,
            )[0]
            for a in ACTIONS
        ]
    ll = loglik_many(stack_models(MODELS[key]), [inv.transform(segments[i].xyz)])[0]
    return ACTIONS[int(np.argmax(ll))]


def test_nested_cv_equals_brute_force(segments, cv):
    labels = [s.action for s in segments]
    cands = [(f, s) for f in FEATURES for s in SETTINGS]
    for fold in cv.folds.iloc[[0, 4]].itertuples():  # a grasp and a tap held out (every fold: too slow)
        i = next(
            k
            for k, s in enumerate(segments)
            if (s.start, s.end, s.recording) == (fold.start, fold.end, fold.recording)
        )
        inner = {}
        for f, st in cands:
            hits = [
                brute_predict(segments, f, st, 0, j, {i, j}) == labels[j]
                for j in range(len(segments))
                if j != i
            ]
            inner[(f, st)] = np.mean(hits)
        best = max(cands, key=lambda c: (inner[c], -cands.index(c)))  # ties to the first candidate
        assert fold.chosen == f"{best[0]}, {best[1]}"
        assert fold.inner_accuracy == pytest.approx(inner[best])
        assert fold.predicted == brute_predict(segments, *best, 0, i, {i})
    (row,) = cv.summary.itertuples()
    assert len(cv.folds) == len(segments) and set(cv.folds.chosen) <= {f"{f}, {s}" for f, s in cands}
    assert (row.correct, row.testable) == (int(cv.folds.correct.sum()), len(segments))
    assert (row.ci_low, row.ci_high) == pytest.approx(clopper_pearson(row.correct, row.testable))
    assert row.always_tap == pytest.approx(1 / 2)


def test_plain_leave_one_out_is_what_tuning_reports(segments, cv):
    labels = [s.action for s in segments]
    for r in cv.candidates.itertuples():
        hits = [
            brute_predict(segments, r.features, r.setting, 0, j, {j}) == labels[j]
            for j in range(len(segments))
        ]
        assert r.loso_accuracy == pytest.approx(np.mean(hits))
    best = cv.candidates.loc[cv.candidates.loso_accuracy.idxmax()]
    assert cv.summary.tuned_accuracy.iloc[0] == best.loso_accuracy


def test_the_seated_report(segments, cv):
    taps = list(synthetic_corpus(1, seed=9, actions=("tap",)))
    rep = nested.seated_report(segments, taps, cv, CONFIG)
    (r,) = rep.itertuples()
    assert r.candidate == cv.summary.tuned_candidate.iloc[0] and r.always_tap
    assert r.below == pytest.approx(r.training_low - r.per_frame)
    assert 1 <= r.onset <= r.n_frames and 0 <= r.p_tap <= 1
    assert (r.predicted == "tap") == (r.tap_from is not None and not np.isnan(r.tap_from))


def test_onset_frame():
    x = np.zeros((10, 3))
    x[4:, 0] = np.linspace(0.05, 1.0, 6)  # still for four frames, then a movement of one unit
    assert nested.onset_frame(x) == 6  # the first frame more than a tenth of the way out
    assert nested.onset_frame(np.zeros((3, 3))) == 1


def test_a_segment_alone_of_its_action_is_left_out(segments):
    """One tap only: held out, tap has nothing to train on, so it is no outer fold, and the inner
    leave-one-segment-out skips it too; the grasps are tested."""
    grasps = [s for s in segments if s.action == "grasp"]
    one_tap = [*grasps, next(s for s in segments if s.action == "tap")]
    cv = nested.nested_cv(one_tap, ("raw",), ("reg0.01",), seeds=(0,), config=CONFIG)
    assert cv.folds.action.tolist() == ["grasp"] * len(grasps)
    assert cv.summary.testable.tolist() == [len(grasps)] and cv.summary.always_tap.tolist() == [0.0]
