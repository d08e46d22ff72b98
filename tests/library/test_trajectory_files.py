"""Own recordings: CSV/TSV/NPY trajectories and skeletons read as the YARP logs are; unfamiliar gestures
flagged."""

from __future__ import annotations

import json

import numpy as np
import pytest

from glu.cli import main
from glu.data.hand_logs import read_hand_log
from glu.errors import DataError
from glu.gestures.features import (
    HORIZONTAL_FALLBACK,
    OPENNI_JOINTS,
    VERTICAL_FALLBACK,
    skeleton_features,
)
from glu.gestures.recordings import load_features
from glu.gestures.synthetic import synthesize_gesture
from glu.hmm import TrainingConfig

METRES = np.array([HORIZONTAL_FALLBACK, VERTICAL_FALLBACK, HORIZONTAL_FALLBACK])


def _segment(source):
    """A recorded segment of the source as (timestamps, logged coordinates): tap1_hand frames 216–351."""
    log = read_hand_log(source.hand_log("tap1_hand"))
    return log.t[215:351], log.xyz[215:351]


def _write_table(path, t, xyz, sep=","):
    lines = [sep.join(["t", "x", "y", "z"])]
    lines += [sep.join(repr(float(v)) for v in (ti, *row)) for ti, row in zip(t, xyz, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def recogniser(source):
    """The originals' models with the real data; one trained by glu on synthetic gestures otherwise."""
    from glu.gestures.corpus import synthetic_corpus
    from glu.gestures.recognizer import load_original_models, train_recognizer

    if source.original_hmms(3) is not None:
        return load_original_models(source.original_hmms(3))
    seqs = synthetic_corpus(6, 0)
    by_action = {a: [s.xyz for s in seqs if s.action == a] for a in dict.fromkeys(s.action for s in seqs)}
    return train_recognizer(by_action, TrainingConfig(n_states=4, n_mix=1, n_iter=20), warn=False)


@pytest.mark.parametrize("suffix", [".csv", ".tsv", ".npy"])
def test_a_table_of_a_real_segment_is_recognised_exactly_as_its_log(source, recogniser, tmp_path, suffix):
    t, logged = _segment(source)
    log = tmp_path / "seg.log"
    log.write_text(
        "".join(
            " ".join(["-1", *(repr(float(v)) for v in (ti, *row))]) + "\n"
            for ti, row in zip(t, logged, strict=True)
        )
    )
    metres = logged / 1000 * METRES  # the hand in the torso frame, in metres (the originals' body size)
    if suffix == ".npy":
        table = tmp_path / "seg.npy"
        np.save(table, np.column_stack([t, metres]))
    else:
        table = _write_table(tmp_path / f"seg{suffix}", t, metres, "," if suffix == ".csv" else "\t")
    from_log = load_features(log, policy=None).pieces[0]
    from_table = load_features(table, policy=None).pieces[0]
    np.testing.assert_array_equal(from_table.t, from_log.t)
    np.testing.assert_allclose(from_table.xyz, from_log.xyz, rtol=1e-14, atol=1e-15)
    ll_log, ll_table = recogniser.loglik(from_log.xyz), recogniser.loglik(from_table.xyz)
    np.testing.assert_allclose(ll_table, ll_log, rtol=1e-12)
    assert recogniser.classify(from_table.xyz) == recogniser.classify(from_log.xyz)
    np.testing.assert_allclose(recogniser.p_hmm(from_table.xyz), recogniser.p_hmm(from_log.xyz), atol=1e-12)


def test_a_skeleton_table_gives_the_skeleton_features(tmp_path):
    g = synthesize_gesture("tap", np.random.default_rng(3), dropout_rate=0.0, spike_rate=0.0)
    skel = g.skeleton
    names = ("torso", "right_hand", "left_shoulder", "right_shoulder", "neck")
    cols = ["t"] + [f"{j}_{a}" for j in names for a in "xyz"]
    t = np.arange(len(skel)) / 30
    rows = [
        [ti] + [skel[i, OPENNI_JOINTS.index(j), k] for j in names for k in range(3)] for i, ti in enumerate(t)
    ]
    path = tmp_path / "skeleton.csv"
    path.write_text(
        ",".join(cols) + "\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in rows) + "\n"
    )
    expected, _ = skeleton_features(skel)
    got = load_features(path, policy=None).pieces[0].xyz
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    np.save(tmp_path / "skeleton.npy", skel)
    np.testing.assert_allclose(load_features(tmp_path / "skeleton.npy", policy=None).pieces[0].xyz, expected)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("x,y,z\n1,2,3\n", "no column 't'"),
        ("t,x,y,z\n0,1,2,3\n0,1,2,3\n", "row 3: t must be finite and strictly increasing"),
        ("t,x,y,z\n0,1,2,nan\n", "row 2: x, y, z must be finite"),
        ("t,a,b\n0,1,2\n", "expected columns t, x, y, z"),
        ("t,x,y,z\n0,1,two,3\n", "not a table of numbers"),
    ],
)
def test_malformed_tables_are_one_line(tmp_path, content, message):
    p = tmp_path / "bad.csv"
    p.write_text(content)
    with pytest.raises(DataError, match=message) as e:
        load_features(p, policy=None)
    assert "\n" not in str(e.value)


def test_recognize_warns_about_a_gesture_unlike_the_training_data(source, recogniser, tmp_path, capsys):
    t, logged = _segment(source)
    metres = logged / 1000 * METRES
    models = "original"
    if source.original_hmms(3) is None:
        models = str(recogniser.save(tmp_path / "rec.json"))
    data = ["--data", str(source.root)]
    good = _write_table(tmp_path / "good.csv", t, metres)
    assert main(["recognize", str(good), "--models", models, "--json", *data]) == 0
    verdict = json.loads(capsys.readouterr().out)["typicality"]
    assert verdict["outside"] is False
    bad = _write_table(tmp_path / "decimetres.csv", t, metres * 10)  # the same gesture in the wrong unit
    assert main(["recognize", str(bad), "--models", models, "--json", *data]) == 0
    out, err = capsys.readouterr()
    verdict = json.loads(out)["typicality"]
    assert verdict["outside"] is True and verdict["per_frame_loglik"] < verdict["reference_range"][0] - 15
    assert "looks like nothing the models were trained on" in err
    assert main(["recognize", str(bad), "--models", models, *data]) == 0
    assert "warning: per-frame log L" in capsys.readouterr().err


def test_a_trained_recogniser_keeps_its_training_range(recogniser, tmp_path):
    from glu.gestures.recognizer import Recognizer
    from glu.gestures.typicality import META_KEY

    back = Recognizer.load(recogniser.save(tmp_path / "r.json"))
    ranges = back.reference_ranges()
    assert set(ranges) == set(back.actions)
    assert back.meta[META_KEY]["reference"] in ("training", "sampled")
    assert all(r.low <= r.high for r in ranges.values())


def test_an_npy_of_x_y_z_is_read_at_30_frames_a_second(tmp_path):
    from glu.data.trajectory_files import read_trajectory_table

    xyz = np.array([[0.1, -0.2, -0.3], [0.11, -0.2, -0.31], [0.12, -0.21, -0.32]])
    np.save(tmp_path / "hand.npy", xyz)
    table = read_trajectory_table(tmp_path / "hand.npy")
    assert table.kind == "hand"
    np.testing.assert_array_equal(table.t, [0.0, 1 / 30, 2 / 30])
    np.testing.assert_array_equal(table.hand, xyz)


@pytest.mark.parametrize(
    ("name", "write", "message"),
    [
        ("missing.npy", None, "missing.npy: no such file"),
        ("text.npy", lambda p: p.write_text("t,x,y,z\n"), "text.npy: not a NumPy array file"),
        (
            "flat.npy",
            lambda p: np.save(p, np.zeros(5)),
            r"flat.npy: an array of shape \(5,\); expected \(T, 4\)",
        ),
        ("wide.npy", lambda p: np.save(p, np.zeros((4, 5))), r"an array of shape \(4, 5\)"),
        ("empty.npy", lambda p: np.save(p, np.zeros((0, 4))), "empty.npy: no frames"),
        ("header.csv", lambda p: p.write_text("t,x,y,z\n"), "header.csv: no frames"),
    ],
)
def test_unreadable_or_empty_recordings_are_one_line(tmp_path, name, write, message):
    if write is not None:
        write(tmp_path / name)
    with pytest.raises(DataError, match=message) as e:
        load_features(tmp_path / name, policy=None)
    assert "\n" not in str(e.value)
