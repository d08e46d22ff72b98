"""p_HMM on held-out segments: each reading, and the nested calibration, against models trained one by one."""

from __future__ import annotations

import numpy as np
import pytest

from glu.errors import DataError
from glu.gestures.calibration import fit_temperature
from glu.gestures.corpus import synthetic_corpus
from glu.hmm import TrainingConfig, loglik_many, stack_models, train
from glu.studies.corpus_evaluation.p_hmm_readings import segment_calibration, segment_readings

CONFIG = TrainingConfig(n_states=2, n_mix=1, n_iter=3)
ACTIONS = ("grasp", "tap")


def softmax(s):
    e = np.exp(s - s.max())
    return e / e.sum()


def test_readings_equal_models_trained_fold_by_fold():
    segs = list(synthetic_corpus(3, seed=11, noise=0.06, actions=ACTIONS))
    table = segment_readings(segs, CONFIG, seed=0)
    labels = np.array([ACTIONS.index(s.action) for s in segs])

    def ll(i, without):
        models = [
            train(
                [s.xyz for j, s in enumerate(segs) if s.action == a and j not in without], CONFIG, warn=False
            )[0]
            for a in ACTIONS
        ]
        return loglik_many(stack_models(models), [segs[i].xyz])[0]

    for i in (0, 4):  # a grasp and a tap, each left out
        rows = table[(table.start == segs[i].start) & (table.recording == segs[i].recording)].set_index(
            "reading"
        )
        outer = ll(i, {i})
        inner = np.array([ll(j, {i, j}) for j in range(len(segs)) if j != i])
        beta = fit_temperature(inner, np.delete(labels, i))
        t = len(segs[i].xyz)
        for reading, p in (
            ("likelihood", softmax(outer)),
            ("per-frame", softmax(outer / t)),
            ("calibrated", softmax(beta * outer)),
        ):
            assert rows.loc[reading, "p_true"] == pytest.approx(p[labels[i]], rel=1e-9, abs=1e-12)
            assert rows.loc[reading, "correct"] == (int(np.argmax(p)) == labels[i])
        assert rows.loc["calibrated", "beta"] == pytest.approx(beta)
    summary = segment_calibration(table, bins=5).set_index("reading")
    lik = table[table.reading == "likelihood"]
    assert summary.loc["likelihood", "accuracy"] == pytest.approx(lik.correct.mean())
    assert summary.loc["likelihood", "certain"] == int((lik.confidence >= 0.99).sum())
    conf, ok = lik.confidence.to_numpy(), lik.correct.to_numpy(dtype=float)
    b = np.minimum((conf * 5).astype(int), 4)
    ece = sum(abs(ok[b == k].sum() - conf[b == k].sum()) for k in range(5)) / len(lik)
    assert summary.loc["likelihood", "ece"] == pytest.approx(ece)


def test_an_action_with_one_segment_is_not_scored():
    """One tap: held out, tap has no model, so no row; the grasps are scored, their inner folds without it."""
    segs = list(synthetic_corpus(3, seed=11, noise=0.06, actions=ACTIONS))
    one_tap = [s for s in segs if s.action == "grasp"] + [next(s for s in segs if s.action == "tap")]
    table = segment_readings(one_tap, CONFIG, seed=0)
    assert set(table.action) == {"grasp"} and len(table) == 3 * table.reading.nunique()


def test_a_segment_whose_temperature_has_nothing_to_fit_on_is_not_scored():
    """Two grasps and a tap: a held-out grasp has a model (the other grasp), but no other segment can be
    scored without both it and that one, so it has no temperature and no row; the tap has no model without it.
    Nothing can be scored, which is said in one line (fit_temperature's shape error before)."""
    segs = list(synthetic_corpus(3, seed=11, noise=0.06, actions=ACTIONS))
    two_grasps = [s for s in segs if s.action == "grasp"][:2] + [next(s for s in segs if s.action == "tap")]
    with pytest.raises(DataError, match=r"^no segment can be scored \(segments per action: grasp 2, tap 1\)"):
        segment_readings(two_grasps, CONFIG, seed=0)
    three_taps = two_grasps + [s for s in segs if s.action == "tap"][1:3]  # grasps scored with the taps' help
    table = segment_readings(three_taps, CONFIG, seed=0)
    assert sorted(table.action.unique()) == ["grasp", "tap"] and (table.action == "grasp").sum() == 2 * 3
