"""The experiments that train many models at once (EM batched) against training each model alone.

The reference path here is the one-model one: :func:`glu.hmm.train` on one model's list of sequences (the
reference EM of :mod:`glu.hmm.em`, by either recipe), and :meth:`Recognizer.loglik` per sequence.
"""

from __future__ import annotations

import numpy as np
import pytest

from glu.gestures.corpus import synthetic_corpus
from glu.gestures.invariants import Invariants
from glu.gestures.recognizer import Recognizer
from glu.hmm import TrainingConfig, train
from glu.hmm.model import GestureHMM

SMALL = TrainingConfig(n_states=3, n_mix=2, n_iter=10, tol=1e-3)


def _alone(seqs, name, seed, recipe, config):
    return train(seqs, config.replace(recipe=recipe), seed=seed, name=name, warn=False).model


def _assert_same_model(m, ref):
    for a in ("startprob", "transmat", "weights", "means", "covars"):
        np.testing.assert_allclose(getattr(m, a), getattr(ref, a), rtol=1e-8, atol=1e-12, err_msg=a)


@pytest.mark.parametrize(("recipe", "features"), [("glu", "raw"), ("glu", "centred"), ("mixsplit", "raw")])
def test_leave_one_segment_out_equals_training_every_fold_alone(recipe, features):
    from glu.studies.replication.recipes import leave_one_segment_out

    corpus = synthetic_corpus(3, seed=4)
    spec = Invariants.parse(features)
    seen = [s.xyz if spec.is_raw else spec.transform(s.xyz) for s in corpus]
    actions = tuple(dict.fromkeys(s.action for s in corpus))
    full = {
        a: _alone([x for x, s in zip(seen, corpus, strict=True) if s.action == a], a, 1, recipe, SMALL)
        for a in actions
    }
    expected = []
    for i, held in enumerate(corpus):
        rest = [
            x for j, (x, s) in enumerate(zip(seen, corpus, strict=True)) if j != i and s.action == held.action
        ]
        models = {**full, held.action: _alone(rest, held.action, 1, recipe, SMALL)}
        expected.append(Recognizer(models, features=spec).classify(held.xyz))
    loso, everything = leave_one_segment_out(
        corpus, seed=1, config=SMALL.replace(recipe=recipe), features=features
    )
    assert list(loso["predicted"]) == expected
    for a in actions:
        _assert_same_model(everything.models[a], full[a])


def test_a_segment_alone_of_its_action_is_not_testable():
    """One grasp only: held out, grasp has nothing to train on; its row says so (no prediction, not testable,
    not correct), and the others are tested."""
    from glu.studies.replication.recipes import leave_one_segment_out

    corpus = synthetic_corpus(3, seed=4)
    grasps = [i for i, s in enumerate(corpus) if s.action == "grasp"]
    corpus = [s for i, s in enumerate(corpus) if i not in grasps[1:]]
    loso, _ = leave_one_segment_out(corpus, seed=1, config=SMALL)
    alone = loso[loso.action == "grasp"]
    assert alone.predicted.isna().tolist() == [True]
    assert alone.testable.tolist() == [False] and alone.correct.tolist() == [False]
    others = loso[loso.action != "grasp"]
    assert others.testable.all() and others.predicted.notna().all()


def test_cross_validation_equals_training_every_fold_alone():
    from glu.studies.replication.gestures import cross_validate, stratified_folds

    corpus = synthetic_corpus(4, seed=8)
    pred = cross_validate(corpus, k=2, seed=3, config=SMALL)
    folds = stratified_folds([s.action for s in corpus], 2, 3)
    actions = tuple(dict.fromkeys(s.action for s in corpus))
    for f in range(2):
        train = [s for s, g in zip(corpus, folds, strict=True) if g != f]
        models = {a: _alone([s.xyz for s in train if s.action == a], a, 3, "glu", SMALL) for a in actions}
        rec = Recognizer(models)
        got = pred[pred["fold"] == f]
        test = [s for s, g in zip(corpus, folds, strict=True) if g == f]
        ll = np.array([rec.loglik(s.xyz) for s in test])
        np.testing.assert_allclose(got[[f"loglik_{a}" for a in actions]].to_numpy(), ll, rtol=1e-9)
        assert list(got["predicted"]) == [rec.classify(s.xyz) for s in test]


def test_correspondence_study_equals_training_every_recogniser_alone():
    from glu.schema import ACTIONS
    from glu.studies.correspondence import experiment as corr

    conds = [c for c in corr.default_conditions() if c.level in ("0°", "mirrored")]
    settings = TrainingConfig(n_states=3, n_mix=1, n_iter=8, tol=1e-3)
    study = corr.correspondence_study(
        train_sources=("human",),
        feature_sets=("raw", "all"),
        conditions=conds,
        seeds=(0, 1),
        n_train=3,
        n_test=2,
        config=settings,
    )
    for seed in (0, 1):
        corpus = corr.training_corpus("human", 3, seed)
        tests = [
            synthetic_corpus(
                2,
                corr._test_seed(seed),
                view=c.view,
                noise=c.noise,
                spike_rate=c.spike_rate,
                dropout_rate=c.dropout_rate,
            )
            for c in conds
        ]
        for features in ("raw", "all"):
            spec = Invariants.parse(features)
            models = {
                a: _alone(
                    [spec.transform(s.xyz) if not spec.is_raw else s.xyz for s in corpus if s.action == a],
                    a,
                    seed,
                    "glu",
                    settings,
                )
                for a in ACTIONS
            }
            rec = Recognizer(models, features=spec)
            for c, test in zip(conds, tests, strict=True):
                acc = np.mean([rec.classify(s.xyz) == s.action for s in test])
                row = study[
                    (study["seed"] == seed) & (study["features"] == spec.name) & (study["level"] == c.level)
                ]
                assert row["accuracy"].item() == acc


def test_loglik_many_equals_loglik_of_each_sequence_even_when_it_underflows():
    """A batch with sequences of different lengths, one of which underflows the scaled recursion of one model
    (it starts on the last state's mean, 100 standard deviations from the first state's)."""
    stay = np.array([[0.9, 0.1], [0.0, 1.0]])

    def hmm(shift):
        means = np.array([[[shift] * 3], [[shift + 100.0] * 3]])
        return GestureHMM([1.0, 0.0], stay, np.ones((2, 1)), means, np.tile(np.eye(3), (2, 1, 1, 1)))

    rec = Recognizer({"a": hmm(0.0), "b": hmm(1.0)})
    rng = np.random.default_rng(0)
    seqs = [rng.normal(size=(n, 3)) + np.linspace(0, 100, n)[:, None] for n in (30, 5, 17, 1)]
    seqs.append(np.vstack([np.full((1, 3), 100.0), rng.normal(size=(6, 3))]))
    expected = np.array([rec.loglik(x) for x in seqs])
    assert np.isfinite(expected).all()
    np.testing.assert_allclose(rec.loglik_many(seqs), expected, rtol=1e-12)
    assert rec.loglik_many([]).shape == (0, 2)
