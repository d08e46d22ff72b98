"""Evaluation helpers: folds, confusion matrices, cross-validation and leave-one-out bookkeeping."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.errors import DataError
from glu.gestures.corpus import LabelledSequence, synthetic_corpus
from glu.hmm import TrainingConfig
from glu.studies.replication.gestures import (
    accuracy,
    confusion_matrix,
    cross_validate,
    leave_one_out,
    stratified_folds,
    wilson_interval,
)

SMALL = {"config": TrainingConfig(n_states=3, n_mix=1, n_iter=15)}


def test_stratified_folds_balance_each_action():
    labels = ["a"] * 10 + ["b"] * 7
    folds = stratified_folds(labels, 3, seed=1)
    for lab, n in (("a", 10), ("b", 7)):
        counts = np.bincount(folds[np.array(labels) == lab], minlength=3)
        assert counts.sum() == n and counts.max() - counts.min() <= 1
    np.testing.assert_array_equal(folds, stratified_folds(labels, 3, seed=1))
    with pytest.raises(DataError, match="cannot fill"):
        stratified_folds(["a", "a", "b"], 3)
    with pytest.raises(DataError, match="k=1: cross-validation needs at least 2 folds"):
        stratified_folds(labels, 1)


def test_bad_arguments_and_sources_are_refused(synthetic_folder):
    from glu.data import resolve_data
    from glu.studies.replication.gestures import original_scores

    with pytest.raises(DataError, match="by='fold'; allowed: 'recording', 'segment'"):
        leave_one_out(synthetic_corpus(2, seed=2), by="fold", **SMALL)
    with pytest.raises(DataError, match="the data source has no original HMMs with M = 3 \\("):
        original_scores(resolve_data(synthetic_folder))


def test_a_recording_without_segments_has_one_row():
    """A recording where segmentation found nothing is one row (segment 0, no action), not left out."""
    from types import SimpleNamespace

    from glu.studies.replication.gestures import segmentation_table

    seg = SimpleNamespace(recording="r", segments=[], events=[])
    table = segmentation_table([(seg, [(1, 10), (20, 30)])], "test")
    assert len(table) == 1
    row = table.iloc[0]
    assert (row.recording, row.segment, row.n_reference) == ("r", 0, 2) and pd.isna(row.action)


def test_confusion_matrix_counts():
    pred = pd.DataFrame(
        {"action": ["tap", "tap", "grasp", "touch"], "predicted": ["tap", "grasp", "grasp", "tap"]}
    )
    pred["correct"] = pred.action == pred.predicted
    cm = confusion_matrix(pred, ["grasp", "tap", "touch"])
    assert cm.loc["tap", "tap"] == 1 and cm.loc["tap", "grasp"] == 1 and cm.loc["touch", "tap"] == 1
    assert cm.loc["touch", "touch"] == 0 and cm.values.sum() == 4
    assert accuracy(pred) == 0.5


@pytest.mark.parametrize(("k", "n"), [(59, 60), (0, 20), (20, 20), (11, 20)])
def test_wilson_interval_is_the_closed_form(k, n):
    z = 1.959963984540054  # the 97.5 % quantile of the standard normal
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    np.testing.assert_allclose(wilson_interval(k, n), (centre - half, centre + half), atol=1e-12)
    assert all(np.isnan(wilson_interval(0, 0)))


def test_cross_validation_predicts_every_sequence_once():
    seqs = synthetic_corpus(4, seed=2, actions=("grasp", "tap"))
    pred = cross_validate(seqs, k=2, seed=0, **SMALL)
    assert len(pred) == 8 and sorted(pred.recording) == sorted(s.recording for s in seqs)
    assert set(pred.fold) == {0, 1}
    np.testing.assert_allclose(pred[["p_hmm_grasp", "p_hmm_tap"]].sum(axis=1), 1.0)
    assert (pred.correct == (pred.action == pred.predicted)).all()


def test_leave_one_recording_out_marks_untestable_actions():
    rng = np.random.default_rng(0)

    def seq(action, rec, shift):
        return LabelledSequence(action, rng.normal(size=(40, 3)) + shift, rec, 1, 40)

    seqs = [
        seq("tap", "r1", 0),
        seq("tap", "r1", 0),
        seq("tap", "r2", 0),
        seq("grasp", "r3", 5),
        seq("grasp", "r3", 5),
    ]
    df = leave_one_out(seqs, by="recording", **SMALL)
    assert df.set_index("held_out").testable.groupby(level=0).first().to_dict() == {
        "r1": True,
        "r2": True,
        "r3": False,
    }
    assert df[~df.testable].predicted.isna().all()
    seg = leave_one_out(seqs, by="segment", **SMALL)
    assert len(seg) == 5 and seg.testable.all()
    # the grasp sequences sit 5 units away from the taps: leave-one-segment-out must find that
    assert seg[seg.action == "grasp"].correct.all()


def test_notebook_08s_banks_are_the_originals_and_both_recipes_on_the_standing_recordings(source):
    """anticipation_banks: the originals' HMMs when the data has them, then glu's recipe and mixsplit with
    the same settings and features, trained on the standing recordings only (as train_on of them)."""
    from glu.gestures.corpus import gesture_sequences
    from glu.studies.replication.gestures import anticipation_banks, recognizer_settings, train_on

    config = TrainingConfig(n_states=2, n_mix=1, n_iter=3)
    banks = anticipation_banks(source, config, 3, seed=1, features="centred")
    originals = ["original"] if source.original_hmms() is not None else []
    assert list(banks) == [*originals, "glu", "mixsplit"]
    for name in ("glu", "mixsplit"):
        s = recognizer_settings(banks[name])
        assert (s["recipe"], s["n_states"], s["n_iter"], s["seed"]) == (name, 2, 3, 1)
        assert banks[name].features.name == "centred"
    standing = gesture_sequences(source, n_per_action=3, seed=1, include_test=False)
    by_hand = train_on(standing, config, seed=1, features="centred")
    x = standing[0].xyz
    np.testing.assert_array_equal(banks["glu"].loglik(x), by_hand.loglik(x))
