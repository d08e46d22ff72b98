"""Invariant gesture features: each formula against a closed form, exact invariance under the generator's
own views, batch equal to streaming, and the recogniser that applies them (checked against hmmlearn)."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from hmm_reference import to_hmmlearn

from glu.errors import DataError, ModelError
from glu.gestures.invariants import INVARIANCES, Invariants
from glu.gestures.recognizer import Recognizer, train_recognizer
from glu.gestures.synthetic import View, synthesize_gesture
from glu.hmm import TrainingConfig

COMBINATIONS = [c for r in range(len(INVARIANCES) + 1) for c in itertools.combinations(INVARIANCES, r)]


def _rot_y(deg):
    c, s = np.cos(np.deg2rad(deg)), np.sin(np.deg2rad(deg))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _features(view, seed=3, action="tap"):
    rng = np.random.default_rng(seed)
    g = synthesize_gesture(action, rng, noise=0.0, spike_rate=0.0, dropout_rate=0.0, view=view)
    return g.trajectory().xyz


def _walk(seed, n=60):
    rng = np.random.default_rng(seed)
    return np.cumsum(rng.normal(size=(n, 3)) * 0.08, axis=0) + rng.normal(size=3)


# ---------------------------------------------------------------- names
def test_names_are_canonical_and_parsed_in_any_order():
    assert Invariants.parse("rotated, centred").names == ("centred", "rotated")
    assert Invariants.parse("rotated+centred").name == "centred+rotated"
    assert Invariants.parse("all").names == INVARIANCES
    assert Invariants.parse("raw").is_raw and Invariants.parse(None).name == "raw"
    assert Invariants.parse(["mirrored"]) == Invariants(("mirrored",))
    for bad, msg in (("centred,wobbly", "unknown invariance 'wobbly'"), ("centred,centred", "named twice")):
        with pytest.raises(DataError, match=msg):
            Invariants.parse(bad)
    with pytest.raises(DataError, match="lock_radius"):
        Invariants(("rotated",), lock_radius=0.0)
    with pytest.raises(DataError, match="anchor_frames"):
        Invariants(("centred",), anchor_frames=0)


# ---------------------------------------------------------------- closed forms
def test_centred_is_the_displacement_from_the_mean_of_the_first_frames():
    X = _walk(0)
    np.testing.assert_allclose(Invariants(("centred",), anchor_frames=1).transform(X), X - X[0], atol=1e-15)
    k = 4
    start = np.array([X[: min(t, k)].mean(axis=0) for t in range(1, len(X) + 1)])  # independent formula
    np.testing.assert_allclose(Invariants(("centred",), anchor_frames=k).transform(X), X - start, atol=1e-14)
    assert np.array_equal(Invariants().transform(X), X)


def test_rotated_turns_the_first_heading_straight_ahead():
    # a straight movement along the horizontal direction u, then a turn to the right of it
    u = np.array([np.cos(0.7), 0.0, np.sin(0.7)])
    right = np.array([-u[2], 0.0, u[0]])  # right of u (for u = -z this is +x)
    X = np.array([[1.0, 2.0, 3.0] + t * u * 0.1 + max(t - 10, 0) * right * 0.05 for t in range(20)])
    out = Invariants(("centred", "rotated"), anchor_frames=1, lock_radius=0.35).transform(X)
    expected = np.array([[max(t - 10, 0) * 0.05, 0.0, -t * 0.1] for t in range(20)])
    np.testing.assert_allclose(out, expected, atol=1e-12)


def test_scaled_divides_by_the_largest_excursion_so_far():
    X = _walk(1)
    inv = Invariants(("centred", "scaled"), anchor_frames=1, min_scale=0.25)
    d = X - X[0]
    scale = np.maximum(0.25, np.maximum.accumulate(np.linalg.norm(d, axis=1)))
    np.testing.assert_allclose(inv.transform(X), d / scale[:, None], atol=1e-14)
    assert np.linalg.norm(inv.transform(X), axis=1).max() <= 1 + 1e-12


def test_mirrored_reflects_a_start_left_of_the_torso():
    X = _walk(2)
    X[:, 0] -= X[0, 0] + 0.5  # the hand starts at x = -0.5
    out = Invariants(("mirrored",), anchor_frames=1).transform(X)
    np.testing.assert_allclose(out, X * [-1, 1, 1], atol=1e-15)
    Y = X * [-1, 1, 1]  # starts at +0.5: left alone
    np.testing.assert_allclose(Invariants(("mirrored",), anchor_frames=1).transform(Y), Y, atol=1e-15)


# ---------------------------------------------------------------- invariance under the generator's views
@pytest.mark.parametrize("yaw", [35.0, 90.0, 180.0, -120.0])
def test_centred_rotated_features_do_not_see_the_turn(yaw):
    inv = Invariants.parse("centred,rotated")
    front, turned = _features(View(yaw_deg=0.0)), _features(View(yaw_deg=yaw))
    assert not np.allclose(front, turned, atol=1e-3)
    np.testing.assert_allclose(inv.transform(turned), inv.transform(front), atol=1e-10)


def test_uncentred_rotation_is_exact_once_the_heading_is_locked():
    inv = Invariants.parse("rotated")
    front, turned = inv.transform(_features(View(yaw_deg=0.0))), inv.transform(_features(View(yaw_deg=70.0)))
    stream, lock = inv.stream(), None
    for t, x in enumerate(_features(View(yaw_deg=0.0))):
        stream.push(x)
        if stream.heading is not None:
            lock = t
            break
    assert lock is not None and lock > 0
    np.testing.assert_allclose(turned[lock:], front[lock:], atol=1e-10)
    assert not np.allclose(turned[:lock], front[:lock], atol=1e-3)  # before the lock the start is as seen


@pytest.mark.parametrize("yaw", [0.0, 40.0, 150.0])
def test_mirror_images_and_turns_are_undone_together(yaw):
    inv = Invariants.parse("centred,rotated,mirrored")
    plain = _features(View(yaw_deg=0.0))
    other = _features(View(yaw_deg=yaw, mirror=True))
    np.testing.assert_allclose(inv.transform(other), inv.transform(plain), atol=1e-10)
    mirror_only = Invariants.parse("centred,mirrored")
    np.testing.assert_allclose(
        mirror_only.transform(_features(View(yaw_deg=0.0, mirror=True))),
        mirror_only.transform(plain),
        atol=1e-10,
    )


def test_scaled_features_do_not_see_body_size_once_the_hand_has_moved():
    inv = Invariants.parse("centred,scaled")
    small = _features(View(yaw_deg=0.0, size=0.8, normalise_body=False))
    big = _features(View(yaw_deg=0.0, size=1.25, normalise_body=False))
    np.testing.assert_allclose(big, small * 1.25 / 0.8, atol=1e-12)  # fixed normalisation: size stays in
    moved = np.flatnonzero(np.linalg.norm(inv.transform(small), axis=1) >= 0.999)[0]  # both past min_scale
    np.testing.assert_allclose(inv.transform(big)[moved:], inv.transform(small)[moved:], atol=1e-10)


# ---------------------------------------------------------------- online = batch
@pytest.mark.parametrize("names", COMBINATIONS, ids=lambda c: "+".join(c) or "raw")
def test_streaming_equals_batch_for_every_combination(names):
    inv = Invariants(names, lock_radius=0.3)
    for seed, n in ((0, 1), (1, 2), (2, 7), (3, 80)):
        X = _walk(seed, n)
        X[:, 0] *= -1 if seed % 2 else 1  # starts on both sides of the torso
        stream = inv.stream()
        online = np.array([stream.push(x) for x in X])
        np.testing.assert_allclose(online, inv.transform(X), rtol=0, atol=1e-12)
        stream.reset()
        np.testing.assert_allclose(stream.push(X[0]), inv.transform(X[:1])[0], atol=1e-12)


def test_a_frame_only_depends_on_the_frames_before_it():
    inv = Invariants.parse("all", lock_radius=0.3)
    X = _walk(5, 50)
    full = inv.transform(X)
    for t in (1, 3, 10, 30):
        np.testing.assert_allclose(inv.transform(X[:t]), full[:t], atol=1e-14)


# ---------------------------------------------------------------- the recogniser applies them
@pytest.fixture(scope="module")
def trained():
    from glu.gestures.corpus import synthetic_corpus

    corpus = synthetic_corpus(5, seed=1, actions=("grasp", "tap", "touch"))
    by = {a: [s.xyz for s in corpus if s.action == a] for a in ("grasp", "tap", "touch")}
    return by, train_recognizer(
        by, TrainingConfig(n_states=3, n_mix=1, n_iter=10), warn=False, features="centred,rotated"
    )


def test_the_recogniser_scores_its_own_features(trained, tmp_path):
    by, rec = trained
    assert rec.features.name == "centred+rotated" and rec.meta["features"] == "centred+rotated"
    X = by["tap"][0]
    Z = Invariants.parse("centred,rotated").transform(X)
    reference = [to_hmmlearn(rec.models[a]).score(Z) for a in rec.actions]  # hmmlearn on the features
    np.testing.assert_allclose(rec.loglik(X), reference, rtol=1e-9)
    ll, _ = rec.stream().extend(X)
    np.testing.assert_allclose(ll, rec.loglik_curve(X), rtol=1e-10)
    np.testing.assert_allclose(ll[-1], reference, rtol=1e-9)
    again = Recognizer.load(rec.save(tmp_path / "r.json"))
    assert again.features == rec.features
    np.testing.assert_array_equal(again.loglik(X), rec.loglik(X))
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["version"] == 3 and doc["invariants"]["names"] == ["centred", "rotated"]


def test_raw_recognisers_and_version_1_files_are_unchanged(trained, tmp_path):
    by, rec = trained
    raw = Recognizer(rec.models)
    X = by["grasp"][1]
    np.testing.assert_allclose(raw.loglik(X), [rec.models[a].loglik(X) for a in rec.actions], rtol=1e-12)
    d = raw.to_dict()
    d["version"] = 1
    del d["invariants"]
    (tmp_path / "v1.json").write_text(json.dumps(d))
    old = Recognizer.load(tmp_path / "v1.json")
    assert old.features.is_raw
    np.testing.assert_array_equal(old.loglik(X), raw.loglik(X))
    d["version"] = 2
    d["invariants"] = {"names": ["wobbly"]}
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(ModelError, match="malformed invariant features"):
        Recognizer.load(tmp_path / "bad.json")


def test_the_batch_scorer_of_a_recogniser_uses_its_features(trained):
    from glu.hmm.scoring import BatchScorer

    by, rec = trained
    seqs = [by["tap"][0], by["grasp"][1][:30]]
    curves = BatchScorer(rec).loglik_curves(seqs)
    for s, X in enumerate(seqs):
        np.testing.assert_allclose(curves[s, : len(X)], rec.loglik_curve(X), rtol=1e-8)
    raw = BatchScorer([rec.models[a] for a in rec.actions]).loglik_curves(seqs)  # bare models: as given
    assert not np.allclose(raw[0, : len(seqs[0])], curves[0, : len(seqs[0])])


def test_invariant_features_need_three_coordinates_a_frame():
    for spec in ("raw", "centred"):
        with pytest.raises(DataError, match=r"invariant features need shape \(n_frames, 3\), got \(5, 2\)"):
            Invariants.parse(spec).transform(np.zeros((5, 2)))
