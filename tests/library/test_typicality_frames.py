"""The typicality check's hand-feature part: a hand that does not move, axes that do not fit the frame.

Independent references: gestures the same generator (or the same person) produced are never flagged; a
still hand and a trajectory with its vertical (y) and depth (z) axes swapped always are. On the real data
the originals' models are checked against the published standing recordings.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from glu.errors import ModelError
from glu.gestures.corpus import synthetic_corpus
from glu.gestures.recognizer import Recognizer, train_recognizer
from glu.gestures.typicality import FRAMES_KEY, FeatureRanges
from glu.hmm import TrainingConfig

SMALL = TrainingConfig(n_states=4, n_mix=1, n_iter=20)


@pytest.fixture(scope="module")
def trained():
    seqs = synthetic_corpus(8, seed=3)
    by_action = {a: [s.xyz for s in seqs if s.action == a] for a in ("grasp", "tap", "touch")}
    return train_recognizer(by_action, SMALL, warn=False)


def _still(X):
    return np.repeat(X[:1], len(X), axis=0)


def _swap_yz(X):
    return X[:, [0, 2, 1]]


def test_held_out_gestures_of_the_same_people_fit(trained):
    held_out = [s for s in synthetic_corpus(30, seed=77) if s.action != "push"]
    flagged = [(s.action, trained.typicality(s.xyz).problems) for s in held_out]
    assert all(not p for _, p in flagged), flagged


def test_a_still_hand_and_swapped_axes_are_flagged(trained):
    for s in synthetic_corpus(3, seed=78):
        still = trained.typicality(_still(s.xyz))
        assert still.atypical and any("hardly moves" in p for p in still.problems), still
        swapped = trained.typicality(_swap_yz(s.xyz))
        assert any("starts far" in p and "y = " in p for p in swapped.problems), swapped
        assert "warning:" in swapped.message() and "posterior is not meaningful" in swapped.message()


def test_the_ranges_are_those_of_the_training_gestures_and_survive_the_file(trained, tmp_path):
    seqs = synthetic_corpus(8, seed=3)
    k = [max(1, min(10, len(s.xyz) // 10)) for s in seqs]  # the median of the first frames (≤ 10, ≤ T/10)
    starts = np.array(
        [np.median(s.xyz[:n], axis=0) for s, n in zip(seqs, k, strict=True) if s.action != "push"]
    )
    r = trained.feature_ranges()
    np.testing.assert_allclose(r.start_low, starts.min(0))
    np.testing.assert_allclose(r.start_high, starts.max(0))
    extent = min(np.ptp(s.xyz, axis=0).max() for s in seqs if s.action in ("grasp", "tap", "touch"))
    assert r.extent_low == pytest.approx(extent) and r.reference == "training"
    back = Recognizer.load(trained.save(tmp_path / "r.json"))
    assert back.feature_ranges() == r


def test_the_boundary_is_where_the_margin_says():
    r = FeatureRanges((0.0, -1.0, 0.0), (0.1, -0.9, 0.2), 1.0, "training")
    X = np.zeros((5, 3))
    X[:, 1] = -1.0
    X[:, 0] = np.linspace(0.0, 1.0, 5)  # moves 1.0, starts inside (5 frames: the start is the first frame)
    assert r.problems(X) == []
    X[0, 1] = -0.9 + 0.3 - 1e-9  # just within the margin (max(half the width, 0.3)) above the highest start
    assert r.problems(X) == []
    X[0, 1] = -0.9 + 0.3 + 1e-6
    assert "y = " in r.problems(X)[0]
    Y = np.zeros((5, 3))
    Y[:, 0] = np.linspace(0.0, 0.05 - 1e-6, 5)  # under 5 % of the least reference extent
    assert "hardly moves" in r.problems(Y)[0]


@pytest.mark.parametrize(
    "entry",
    [{"start_low": [0, 0], "start_high": [1], "extent_low": 1}, {"start_low": [1], "start_high": [0]}, "x"],
)
def test_malformed_ranges_in_a_file_are_one_clear_error(trained, tmp_path, entry):
    d = trained.to_dict()
    d["meta"][FRAMES_KEY] = entry
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(d))
    with pytest.raises(ModelError, match=f"meta.{FRAMES_KEY}"):
        Recognizer.load(path)


@pytest.mark.shared_data
def test_the_originals_are_checked_against_the_published_recordings(shared_data):
    from glu.data.source import resolve_data
    from glu.gestures.corpus import original_recognizer, real_segments

    source = resolve_data(shared_data)
    rec = original_recognizer(source)
    assert rec.feature_ranges().reference == "published standing"
    standing = real_segments(source, include_original=False)
    assert len(standing) == 13
    for s in standing:  # the data the originals were published with: nothing flagged
        assert not rec.typicality(s.xyz).problems, s.recording
    for s in standing:  # before this check both gave a confident answer and no warning
        assert rec.typicality(_still(s.xyz)).atypical
        assert rec.typicality(_swap_yz(s.xyz)).atypical


def test_the_message_prints_the_distance_and_the_margin_allowed():
    from glu.gestures.typicality import MIN_MARGIN, LoglikRange, Typicality

    r = LoglikRange(-8.0, -3.0, "sampled")  # width 5: the margin is MIN_MARGIN
    near = Typicality("tap", -13.0, r, r.outside(-13.0)).message()
    assert "lies 5.00 nats/frame below the sampled range -8.00 … -3.00" in near
    assert f"(far means more than {MIN_MARGIN:.2f})" in near
    far_x = -8.0 - MIN_MARGIN - 1.0
    far = Typicality("tap", far_x, r, r.outside(far_x)).message()
    assert far.startswith("warning:") and f"lies {MIN_MARGIN + 1:.2f} nats/frame below" in far
    assert "lies inside the sampled range" in Typicality("tap", -4.0, r, False).message()
