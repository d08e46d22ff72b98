"""Per-episode statistics of the corpus evaluation against a direct, episode-by-episode computation."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.bn import learn_bn, make_engine
from glu.data import load_experiments
from glu.errors import DataError, ModelError
from glu.fusion import fuse
from glu.gestures.calibration import Calibration
from glu.hmm import TrainingConfig
from glu.hmm.scoring import BatchScorer
from glu.schema import ACTIONS
from glu.studies.corpus_evaluation.evaluation import (
    EvaluationSettings,
    Evaluator,
    Reading,
    Replication,
    statistic_columns,
    target_tables,
)
from glu.studies.episodes import Condition

SETTINGS = EvaluationSettings(fractions=(0.3, 1.0), bootstrap=25)


def small_recognizer(seed=0, features="raw"):
    """Gesture HMMs trained in a second on a few synthetic gestures (good enough to be informative)."""
    from glu.gestures.corpus import synthetic_corpus
    from glu.gestures.feature_sets import FeatureSet
    from glu.gestures.recognizer import train_recognizer
    from glu.gestures.views import View

    spec = FeatureSet.parse(features)
    corpus = synthetic_corpus(6, seed, view=View(body_frame=spec.body))
    by_action = {a: [s.xyz for s in corpus if s.action == a] for a in ACTIONS}
    config = TrainingConfig(n_states=3, n_mix=1, n_iter=10)
    return train_recognizer(by_action, config, seed=seed, warn=False, features=spec.invariants)


CALIBRATION = Calibration(np.array(SETTINGS.fractions), np.array([0.05, 0.02]), 30)
MATCHED = Calibration(np.array(SETTINGS.fractions), np.array([0.03, 0.01]), 30)
READINGS = (
    Reading("generating", 0, "likelihood"),
    Reading("generating", 0, "per-frame"),
    Reading("generating", 0, "calibrated"),
    Reading("learned", 200, "likelihood"),
    Reading("generating", 0, "calibrated-matched", "centred+rotated"),
    Reading("generating", 0, "per-frame", "body"),
)
FEATURES = ("raw", "centred+rotated", "body")


def replication(seed, tables):
    recs = {f: small_recognizer(seed, f) for f in FEATURES}
    cals = {f: {"calibrated": CALIBRATION, "calibrated-matched": MATCHED} for f in FEATURES}
    return Replication({f: BatchScorer(r) for f, r in recs.items()}, cals, tables), recs


@pytest.fixture(scope="module")
def setup():
    engine = make_engine(learn_bn(load_experiments("synthetic")))
    learned = make_engine(learn_bn(load_experiments("synthetic").iloc[:200]))
    tables = {"generating": target_tables(engine, SETTINGS), "learned-200": target_tables(learned, SETTINGS)}
    first, recs = replication(0, tables)
    rec = recs["raw"]
    replications = (first, replication(1, tables)[0])
    ev = Evaluator(engine, replications, READINGS, SETTINGS, seed=5, chunk_size=12)
    chunk = ev.simulate(Condition(0.03, "turned"), 0, 12)
    return engine, rec, ev, chunk, ev.episode_statistics(chunk)[0], learned, recs


def column_values(ev, blocks):
    """The per-episode statistics as a frame with the statistics' description as columns."""
    X = np.concatenate(blocks, axis=1)
    cols = ev.columns
    return pd.DataFrame(X, columns=pd.MultiIndex.from_frame(cols.astype(str)))


def cell(frame, target, strategy, fraction, stat, b=-1):
    return frame[(target, strategy, str(fraction), stat, str(b))].to_numpy()


def test_statistics_equal_a_direct_computation(setup):
    engine, rec, ev, chunk, blocks, *_ = setup
    frame = column_values(ev, blocks)
    assert frame.shape[1] == len(ev.columns)
    schema = engine.bn.schema
    for i, x in enumerate(chunk.features):
        row = {
            n: schema.values_of(n)[chunk.codes[n][i]] for n in ("Action", "Color", "Shape", "Size", "ObjVel")
        }
        for f in SETTINGS.fractions:
            t = max(int(np.ceil(round(f * len(x), 9))), 1)
            q = rec.p_hmm(x[:t])  # the per-sequence path
            a_true = ACTIONS.index(row["Action"])
            # action: gesture alone, and the product rule on the network's evidence
            assert cell(frame, "action", "gesture", f, "correct")[i] == float(np.argmax(q) == a_true)
            assert cell(frame, "action", "gesture", f, "log_loss")[i] == pytest.approx(
                -np.log(max(q[a_true], 1e-6)), rel=1e-9
            )
            obs = {k: row[k] for k in SETTINGS.action_evidence}
            p = fuse(engine, "Action", obs, q, "product")["Action"]
            assert cell(frame, "action", "product", f, "brier")[i] == pytest.approx(
                ((p - np.eye(3)[a_true]) ** 2).sum(), rel=1e-9
            )
            # effect: virtual evidence before the effect
            obs = {k: row[k] for k in SETTINGS.effect_evidence}
            p = fuse(engine, "ObjVel", obs, q, "virtual")["ObjVel"]
            y = schema.values_of("ObjVel").index(row["ObjVel"])
            assert cell(frame, "effect", "virtual", f, "log_loss")[i] == pytest.approx(
                -np.log(max(p[y], 1e-6)), rel=1e-9
            )
            if f == 1.0:  # calibration bins at the full gesture
                b = min(int(p.max() * SETTINGS.bins), SETTINGS.bins - 1)
                assert cell(frame, "effect", "virtual", f, "bin_n", b)[i] == 1.0
                assert cell(frame, "effect", "virtual", f, "bin_confidence", b)[i] == pytest.approx(p.max())
                b = min(int(q.max() * SETTINGS.bins), SETTINGS.bins - 1)
                assert cell(frame, "action", "gesture", f, "bin_correct", b)[i] == float(
                    np.argmax(q) == a_true
                )
            # words: Jeffrey's rule's probability of each word, against the words said (Bernoulli)
            obs = {k: row[k] for k in SETTINGS.words_evidence}
            allowed = engine.query("Action", obs)["Action"] > 0  # Jeffrey's rule on the actions obs allows
            wp = engine.word_probability_array(obs, {"Action": q * allowed / (q * allowed).sum()}, "jeffrey")
            said = np.array([chunk.codes[w][i] == 1 for w in engine.binary_leaves])
            p_said = np.where(said, wp, 1 - wp)
            assert cell(frame, "words", "jeffrey", f, "log_loss")[i] == pytest.approx(
                -np.log(np.maximum(p_said, 1e-6)).mean(), rel=1e-9
            )
            assert cell(frame, "words", "jeffrey", f, "brier")[i] == pytest.approx(
                ((wp - said) ** 2).mean(), rel=1e-9
            )


def test_the_readings_of_p_hmm(setup):
    """p_HMM per frame (softmax of (1/t) log L) and calibrated (softmax of β log L), with the per-sequence
    forward."""
    _, rec, ev, chunk, *_ = setup
    per_frame = ev.p_hmm(chunk.features, "per-frame")
    calibrated = ev.p_hmm(chunk.features, "calibrated")
    matched = ev.p_hmm(chunk.features, "calibrated-matched")
    for i, x in enumerate(chunk.features[:5]):
        for j, f in enumerate(SETTINGS.fractions):
            t = max(int(np.ceil(round(f * len(x), 9))), 1)
            ll = rec.loglik(x[:t])
            for q, scaled in (
                (per_frame, ll / t),
                (calibrated, ll * CALIBRATION.beta[j]),
                (matched, ll * MATCHED.beta[j]),
            ):
                e = np.exp(scaled - scaled.max())
                np.testing.assert_allclose(q[i, j], e / e.sum(), rtol=1e-9)
    with pytest.raises(DataError, match="unknown reading"):
        ev.p_hmm(chunk.features, "tempered")


def test_a_learned_network_is_the_robots_model(setup):
    """Under a learned network the effect is predicted by that network (fused with p_HMM), the episodes
    still come from the generating one."""
    engine, rec, ev, chunk, _, learned, _ = setup
    stats = ev.episode_statistics(chunk)[READINGS.index(Reading("learned", 200, "likelihood"))]
    frame = column_values(ev, stats)
    schema = engine.bn.schema
    for i, x in enumerate(chunk.features[:6]):
        row = {n: schema.values_of(n)[chunk.codes[n][i]] for n in ("Color", "Shape", "Size", "ObjVel")}
        q = rec.p_hmm(x)
        obs = {k: row[k] for k in SETTINGS.effect_evidence}
        y = schema.values_of("ObjVel").index(row["ObjVel"])
        for strat in ("virtual", "jeffrey"):
            p = fuse(learned, "ObjVel", obs, q, strat)["ObjVel"]
            assert cell(frame, "effect", strat, 1.0, "log_loss")[i] == pytest.approx(
                -np.log(max(p[y], 1e-6)), rel=1e-9
            )
        p = learned.query("ObjVel", obs)["ObjVel"]
        assert cell(frame, "effect", "network", 1.0, "log_loss")[i] == pytest.approx(
            -np.log(max(p[y], 1e-6)), rel=1e-9
        )


def test_shared_blocks_equal_a_reading_alone(setup):
    """Readings of one network share the gesture-free and hard-decision blocks: each reading's statistics
    equal an evaluator that has only that reading."""
    engine, rec, ev, chunk, *_ = setup
    together = ev.episode_statistics(chunk)
    for r, reading in enumerate(READINGS):
        alone = Evaluator(engine, ev.replications, (reading,), SETTINGS, seed=5, chunk_size=12)
        np.testing.assert_array_equal(
            np.concatenate(alone.episode_statistics(chunk)[0], axis=1),
            np.concatenate(together[r], axis=1),
        )


def test_identities_between_strategies(setup):
    _, _, ev, _, blocks, *_ = setup
    frame = column_values(ev, blocks)
    for f in SETTINGS.fractions:
        for stat in ("correct", "log_loss", "brier"):
            np.testing.assert_allclose(
                cell(frame, "action", "virtual", f, stat),
                cell(frame, "action", "product", f, stat),
                rtol=1e-12,
            )
        # Jeffrey's rule returns p_HMM for the action (on the actions the evidence allows)
        np.testing.assert_array_equal(
            cell(frame, "action", "jeffrey", f, "correct") >= cell(frame, "action", "gesture", f, "correct"),
            True,
        )
        # the network alone and the true action do not depend on the gesture
        for strat in ("network", "true_action"):
            np.testing.assert_array_equal(
                cell(frame, "effect", strat, f, "brier"), cell(frame, "effect", strat, 1.0, "brier")
            )
    assert (
        cell(frame, "words", "network", 1.0, "log_loss") == cell(frame, "words", "network", 0.3, "log_loss")
    ).all()


def test_run_chunk_sums_with_two_level_bootstrap_weights(setup):
    _, _, ev, chunk, blocks, *_ = setup
    sums = ev.run_chunk(Condition(0.03, "turned"), 0, 0, 12)
    assert sums.shape == (len(READINGS), SETTINGS.bootstrap + 1, len(ev.columns))
    np.testing.assert_allclose(sums[0, 0], np.concatenate(blocks, axis=1).sum(axis=0), rtol=1e-12)
    assert sums[0, 0, 0] == 12 and (sums[0, 1:, 0] != 12).any()  # replicates count episodes with weights
    # a replicate that does not draw this seed gives its episodes weight 0
    counts = ev.counts[:, 0]
    assert ev.counts.shape == (SETTINGS.bootstrap + 1, 2) and (ev.counts.sum(axis=1) == 2).all()
    w = ev.weights(0, 0, 12)
    assert (w[:, counts == 0] == 0).all() and (w[:, 0] == 1).all()
    np.testing.assert_array_equal(sums[:, 1:, 0], np.broadcast_to(w[:, 1:].sum(axis=0), (len(READINGS), 25)))
    other = ev.run_chunk(Condition(0.03, "turned"), 1, 0, 12)  # the second seed: its own episodes
    assert not np.array_equal(other[0, 0], sums[0, 0])


def test_columns_and_settings():
    cols = statistic_columns(EvaluationSettings(fractions=(1.0,), strategies=("gesture", "hard"), bins=2))
    assert cols.iloc[0].stat == "n"
    assert set(cols.target) == {"episodes", "action", "effect", "words"}
    assert set(cols[cols.target == "action"].strategy) == {"gesture", "hard"}
    assert len(cols[(cols.target == "effect")]) == 3 + 2 * 3
    two = statistic_columns(EvaluationSettings(fractions=(1.0, 0.5), strategies=("gesture",), bins=2))
    binned = two[two.bin >= 0]
    assert set(binned.fraction) == {1.0} and set(binned.target) == {"action"}  # bins at the full gesture
    for bad, msg in [
        ({"fractions": (0.0,)}, "in \\(0, 1\\]"),
        ({"strategies": ("best",)}, "unknown strategy 'best'"),
        ({"effect_evidence": ("ObjVel",)}, "leave it out"),
        ({"action_evidence": ("Action",)}, "cannot be observed"),
        ({"bootstrap": -1}, "replicates"),
        ({"fractions": (0.5, 0.5)}, "each may appear once"),
        ({"bins": 0}, "bins=0: a whole number from 1 to 100"),
        ({"log_floor": 1}, "log_floor=1: a number in \\(0, 1\\)"),
    ]:
        with pytest.raises(DataError, match=msg):
            EvaluationSettings(**bad)


def test_the_recogniser_must_know_the_networks_actions(setup):
    engine, rec, ev, *_ = setup
    tables = ev.replications[0].tables
    with pytest.raises(ModelError, match="grasp, tap, touch"):
        Replication({"raw": BatchScorer([rec.models[a] for a in ("tap", "grasp", "touch")])}, {}, tables)
    with pytest.raises(DataError, match="no learned-100 network"):
        Evaluator(engine, ev.replications, (Reading("learned", 100, "likelihood"),))
    with pytest.raises(DataError, match="needs every replication's calibration"):
        Evaluator(
            engine, (Replication({"raw": BatchScorer(rec)}, {}, tables),), (Reading(p_hmm="calibrated"),)
        )
    with pytest.raises(DataError, match="feature set 'body'"):
        Evaluator(engine, (Replication({"raw": BatchScorer(rec)}, {}, tables),), (Reading(features="body"),))
    with pytest.raises(DataError, match="learn_experiments"):
        Reading("learned", 0)
    with pytest.raises(DataError, match="unknown feature set 'bodily'"):
        Reading(features="bodily")
    with pytest.raises(DataError, match="unknown inference network 'oracle'; allowed: generating, learned"):
        Reading("oracle")
    with pytest.raises(DataError, match="unknown reading of p_HMM 'raw'; allowed: likelihood, per-frame"):
        Reading(p_hmm="raw")
    with pytest.raises(DataError, match="at least one recogniser"):
        Evaluator(engine, ())
    for readings in [(), (Reading(), Reading())]:
        with pytest.raises(DataError, match="distinct readings"):
            Evaluator(engine, ev.replications, readings)


def test_a_body_feature_set_needs_the_body_frame(setup):
    """Episodes simulated without the shoulder line's frame cannot be seen by a body recogniser."""
    _, _, ev, chunk, *_ = setup
    with pytest.raises(DataError, match="feature set 'body' needs the episodes in the shoulder line's frame"):
        ev.seen(chunk._replace(body_features=None), "body")


def test_each_feature_set_sees_its_own_features(setup):
    """A reading of the feature set ``body`` scores the episodes in the shoulder line's frame with the body
    recogniser; ``centred+rotated`` applies its invariances online; each equals the per-sequence path."""
    _, _, ev, chunk, _, _, recs = setup
    assert chunk.body_features is not None
    for features in ("centred+rotated", "body"):
        r = READINGS.index(next(x for x in READINGS if x.features == features))
        frame = column_values(ev, ev.episode_statistics(chunk)[r])
        xs = chunk.body_features if features == "body" else chunk.features
        for i, x in enumerate(xs[:4]):
            ll = recs[features].loglik(x)  # the recogniser applies its own invariances
            reading = READINGS[r].p_hmm
            scaled = ll * MATCHED.beta[1] if reading == "calibrated-matched" else ll / len(x)
            q = np.exp(scaled - scaled.max())
            q /= q.sum()
            a = ACTIONS.index(ev.world.bn.schema.values_of("Action")[chunk.codes["Action"][i]])
            assert cell(frame, "action", "gesture", 1.0, "log_loss")[i] == pytest.approx(
                -np.log(max(q[a], 1e-6)), rel=1e-9
            )


def test_network_tables_without_evidence_and_with_impossible_evidence():
    """No observed node: one combination, the prior and p(ObjVel | A) by summing the object out of the CPTs
    (words of uniform unseen rows: every word's rows sum to 1, the words sum out); evidence of probability 0
    (no object ever stays still): NaN rows."""
    from dataclasses import replace

    from glu.studies.corpus_evaluation.network_tables import network_tables

    bn = learn_bn(load_experiments("synthetic"), unseen_words="uniform")
    none = network_tables(make_engine(bn), (), "ObjVel")
    shape, size, vel = bn.cpts["Shape"], bn.cpts["Size"], bn.cpts["ObjVel"]
    assert (
        bn.parents["ObjVel"] == ("Action", "Shape", "Size") and not bn.parents["Shape"] + bn.parents["Size"]
    )
    np.testing.assert_allclose(none.p_action, [bn.cpts["Action"]], rtol=1e-12)
    np.testing.assert_allclose(
        none.p_given_action[0], np.einsum("j,k,ajkv->av", shape, size, vel), rtol=1e-12
    )
    assert none.combo({"Color": np.array([0, 2, 1])}, ()).tolist() == [0, 0, 0]
    cpt = vel.copy()
    cpt[..., 0] = 0.0  # slow
    cpt /= cpt.sum(axis=-1, keepdims=True)
    never_still = network_tables(
        make_engine(replace(bn, cpts={**bn.cpts, "ObjVel": cpt})), ("ObjVel",), "Shape"
    )
    assert np.isnan(never_still.p_action[0]).all() and np.isnan(never_still.p_given_action[0]).all()
    assert np.isfinite(never_still.p_action[1:]).all()
