"""The gesture commands: outputs, JSON shape, streaming, and bad input as one line with exit status 2."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_run import run
from hmm_reference import to_hmmlearn

from glu.gestures.corpus import synthetic_corpus
from glu.gestures.features import LOG_SCALE
from glu.gestures.synthetic import synthesize_recording


def _write_log(path, xyz, t):
    lines = [f"-1 {ti:.6f} {x:.6f} {y:.6f} {z:.6f}" for ti, (x, y, z) in zip(t, xyz * LOG_SCALE, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def synthetic_log(tmp_path_factory):
    rec = synthesize_recording("tap", 3, seed=1, noise=0.005)
    tr = rec.trajectory()
    path = _write_log(tmp_path_factory.mktemp("logs") / "data.log", tr.xyz, 1000.0 + tr.t)
    return path, rec


def assert_one_line_error(status, err, *fragments):
    assert status == 2
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for f in fragments:
        assert f in err, err


def test_segment_prints_the_true_repetitions(capsys, synthetic_log, tmp_path):
    path, rec = synthetic_log
    png = tmp_path / "seg.png"
    status, out, _ = run(capsys, "gestures", "segment", str(path), "--plot", str(png), "--label", "tap")
    assert status == 0
    assert "segments: 3" in out
    lines = [ln for ln in out.splitlines() if ln.strip().startswith(("1.", "2.", "3."))]
    for ln, (a, b) in zip(lines, rec.segments, strict=True):
        start, end = map(int, ln.split("frames ")[1].split(" ")[0].split(":"))
        assert a - 5 <= start < end <= b + 5
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_train_and_recognize_with_a_recogniser(capsys, tmp_path, synthetic_log):
    model = tmp_path / "rec.json"
    status, out, _ = run(
        capsys,
        "hmm",
        "train",
        "--synthetic",
        "6",
        "--states",
        "3",
        "--mix",
        "1",
        "--iter",
        "20",
        "-o",
        str(model),
    )
    assert status == 0 and model.exists() and "wrote" in out
    assert "grasp: 6 sequences" in out
    path, rec = synthetic_log
    a, b = rec.segments[1]
    status, out, _ = run(
        capsys, "recognize", str(path), "--frames", f"{a}:{b}", "--models", str(model), "--json"
    )
    assert status == 0
    d = json.loads(out)
    assert set(d) == {"loglik", "posterior", "typicality"}
    assert list(d["loglik"]) == list(d["posterior"]) == ["grasp", "tap", "touch"]
    assert sum(d["posterior"].values()) == pytest.approx(1.0)
    from glu.gestures.recognizer import Recognizer

    X = np.loadtxt(path)[a - 1 : b, 2:] / 1000
    np.testing.assert_allclose(list(d["loglik"].values()), Recognizer.load(model).loglik(X), rtol=1e-12)


@pytest.fixture(scope="module")
def models(source, recognizer, tmp_path_factory):
    """``--models`` for the source: ``original`` with the real data, a saved recogniser file otherwise."""
    if source.original_hmms() is not None:
        return "original"
    return str(recognizer.save(tmp_path_factory.mktemp("models") / "recognizer.json"))


def test_recognize_json_and_stream(capsys, source, recognizer, models):
    common = ["recognize", "tap1_hand", "--data", str(source.root), "--frames", "216:351", "--models", models]
    status, out, err = run(capsys, *common, "--json")
    assert status == 0
    d = json.loads(out)  # stdout is exactly the JSON object; the data source went to stderr
    assert set(d) == {"loglik", "posterior", "typicality"} and list(d["loglik"]) == ["grasp", "tap", "touch"]
    X = np.loadtxt(source.hand_log("tap1_hand"))[215:351, 2:] / 1000  # the logged frames, independently
    np.testing.assert_allclose(list(d["loglik"].values()), recognizer.loglik(X)[:3], rtol=1e-12)
    status, out, _ = run(capsys, *common, "--stream")
    assert status == 0
    rows = [ln.split() for ln in out.splitlines() if ln[:5].strip().isdigit()]
    assert len(rows) == 136 and rows[0][0] == "216" and rows[-1][0] == "351"
    np.testing.assert_allclose([float(v) for v in rows[-1][1:4]], list(d["loglik"].values()), atol=1e-3)
    status, out, _ = run(capsys, *common)
    best = max(d["posterior"], key=d["posterior"].get)
    assert status == 0 and f"recognised: {best}" in out


def test_stream_json_lines(capsys, source, models):
    status, out, _ = run(
        capsys,
        "recognize",
        "tap_notable_seated_1",
        "--data",
        str(source.root),
        "--frames",
        "121:125",
        "--stream",
        "--json",
        "--models",
        models,
    )
    assert status == 0
    lines = [json.loads(ln) for ln in out.splitlines()]
    assert [d["frame"] for d in lines] == [121, 122, 123, 124, 125]
    assert all(set(d) == {"frame", "loglik", "posterior"} for d in lines)


@pytest.mark.parametrize(
    "frames, fragment",
    [("5", "is not A:B"), ("a:b", "is not A:B"), ("10:5", "need 1 ≤ A ≤ B"), ("0:5", "need 1 ≤ A ≤ B")],
)
def test_bad_frames_syntax(capsys, synthetic_log, frames, fragment):
    path, _ = synthetic_log
    status, _, err = run(capsys, "recognize", str(path), "--frames", frames, "--models", "x.json")
    assert_one_line_error(status, err, fragment)


def test_frames_out_of_range(capsys, synthetic_log, source, models):
    path, _ = synthetic_log
    status, _, err = run(
        capsys, "recognize", str(path), "--frames", "1:99999", "--data", str(source.root), "--models", models
    )
    assert_one_line_error(status, err, "out of range; allowed: 1 ≤ first ≤ last ≤")


def test_malformed_log_and_missing_files(capsys, tmp_path, source, models):
    bad = tmp_path / "bad.log"
    bad.write_text("-1 1.0 1 2 3\n-1 1.1 1 2\n")
    status, _, err = run(capsys, "gestures", "segment", str(bad))
    assert_one_line_error(status, err, f"{bad}:2: expected 5 fields")
    data = ["--data", str(source.root), "--models", models]
    status, _, err = run(capsys, "recognize", str(bad), *data)
    assert_one_line_error(status, err, f"{bad}:2:")
    status, _, err = run(capsys, "recognize", str(tmp_path / "none.log"), *data)
    assert_one_line_error(status, err, "none.log: file not found")
    status, _, err = run(capsys, "recognize", "no_such_recording", *data)
    assert_one_line_error(status, err, "recordings: grasp1_hand")
    notjson = tmp_path / "m.json"
    notjson.write_text("{")
    status, _, err = run(capsys, "recognize", str(bad), "--models", str(notjson))
    assert_one_line_error(status, err, "not a JSON recogniser file")


def test_train_arguments(capsys, tmp_path):
    status, _, err = run(capsys, "hmm", "train", "--synthetic", "0", "-o", str(tmp_path / "m.json"))
    assert_one_line_error(status, err, "expected a whole number ≥ 1, not 0")
    status, _, err = run(capsys, "hmm", "train", "--synthetic", "3", "--actions", "tap,wave", "-o", "m.json")
    assert_one_line_error(status, err, "--actions: no synthetic wave; allowed: grasp, tap, touch, push")
    status, _, err = run(capsys, "hmm", "train", "--synthetic", "3", "--actions", "tap,tap", "-o", "m.json")
    assert_one_line_error(status, err, "give distinct action names")
    status, _, err = run(
        capsys, "hmm", "train", "--data", str(tmp_path / "nope"), "-o", str(tmp_path / "m.json")
    )
    assert_one_line_error(status, err, "no such data folder")


def test_train_on_the_recordings(capsys, tmp_path, source):
    model = tmp_path / "trained.json"
    status, out, _ = run(capsys, "hmm", "train", "--data", str(source.root), "-o", str(model), "--iter", "20")
    assert status == 0 and f"data: {source.kind} data" in out
    assert "grasp: 4 sequences" in out and "tap: 3 sequences" in out  # the standing recordings only
    status, out, _ = run(
        capsys,
        "hmm",
        "train",
        "--data",
        str(source.root),
        "-o",
        str(tmp_path / "all.json"),
        "--iter",
        "2",
        "--include-test",
    )
    assert status == 0 and "tap: 5 sequences" in out  # + the two seated taps
    status, out, _ = run(capsys, "recognize", "tap1_hand", "--data", str(source.root), "--models", str(model))
    assert status == 0


def test_train_with_invariant_features_and_recognize(capsys, tmp_path, synthetic_log):
    from glu.gestures.invariants import Invariants
    from glu.gestures.recognizer import Recognizer

    model = tmp_path / "inv.json"
    status, out, _ = run(
        capsys,
        "hmm",
        "train",
        "--synthetic",
        "5",
        "--states",
        "3",
        "--mix",
        "1",
        "--iter",
        "10",
        "--features",
        "rotated,centred",
        "--covar-reg",
        "0.01",
        "-o",
        str(model),
    )
    assert status == 0 and "features: centred+rotated" in out
    rec = Recognizer.load(model)
    assert rec.features.name == "centred+rotated" and rec.config.covar_reg == 0.01
    path, g = synthetic_log
    a, b = g.segments[0]
    args = ["recognize", str(path), "--frames", f"{a}:{b}", "--models", str(model), "--json"]
    status, out, err = run(capsys, *args)
    assert status == 0 and "features centred+rotated" in err
    X = np.loadtxt(path)[a - 1 : b, 2:] / 1000
    Z = Invariants.parse("centred,rotated").transform(X)  # what the models must see
    reference = [to_hmmlearn(rec.models[x]).score(Z) for x in rec.actions]
    np.testing.assert_allclose(list(json.loads(out)["loglik"].values()), reference, rtol=1e-9)
    status, out, _ = run(capsys, *args, "--stream")
    last = json.loads(out.splitlines()[-1])
    assert status == 0 and last["frame"] == b
    np.testing.assert_allclose(list(last["loglik"].values()), reference, rtol=1e-9)


def test_bad_features_are_refused(capsys, tmp_path):
    status, _, err = run(
        capsys,
        "hmm",
        "train",
        "--synthetic",
        "3",
        "--features",
        "centred,wobbly",
        "-o",
        str(tmp_path / "m.json"),
    )
    assert_one_line_error(
        status, err, "unknown invariance 'wobbly'; allowed: centred, scaled, rotated, mirrored"
    )
    assert not (tmp_path / "m.json").exists()


def _recordings(root, n=4, seed=5, actions=("wave", "point")):
    """One folder per action of t,x,y,z tables (metres) made from synthetic grasps and taps."""
    from glu.gestures.features import HORIZONTAL_FALLBACK, VERTICAL_FALLBACK

    metres = np.array([HORIZONTAL_FALLBACK, VERTICAL_FALLBACK, HORIZONTAL_FALLBACK])
    seqs = synthetic_corpus(n, seed, actions=("grasp", "tap"))
    for label, source in zip(actions, ("grasp", "tap"), strict=True):
        (root / label).mkdir(parents=True)
        for i, s in enumerate(x for x in seqs if x.action == source):
            t = np.arange(len(s.xyz)) / 30.0
            table = np.column_stack([t, s.xyz * metres])
            np.savetxt(root / label / f"r{i}.csv", table, delimiter=",", header="t,x,y,z", comments="")
    return seqs


def test_train_on_your_own_labelled_recordings(capsys, tmp_path):
    """A folder per action (named as you like), then a manifest with frames: trained, saved, recognised."""
    seqs = _recordings(tmp_path / "mine")
    model = tmp_path / "mine.json"
    args = ["--states", "3", "--mix", "1", "--iter", "20", "--features", "centred"]
    status, out, err = run(
        capsys, "hmm", "train", "--recordings", str(tmp_path / "mine"), "-o", str(model), *args
    )
    assert status == 0, err
    assert "labelled recordings: mine (8 recordings)" in out and "point: 4 sequences" in out
    from glu.gestures.recognizer import Recognizer

    rec = Recognizer.load(model)
    assert rec.actions == ("point", "wave") and rec.features.name == "centred"
    held = synthetic_corpus(6, 50, actions=("grasp", "tap"))
    correct = [rec.classify(s.xyz) == {"grasp": "wave", "tap": "point"}[s.action] for s in held]
    assert np.mean(correct) >= 0.8, correct  # chance is 1/2
    manifest = tmp_path / "manifest.csv"
    rows = [
        "file,label,frames",
        *(f"mine/wave/r{i}.csv,wave," for i in range(3)),
        "mine/point/r0.csv,point,2:40",
    ]
    manifest.write_text("\n".join(rows) + "\n")
    args = ["--states", "2", "--mix", "1", "--iter", "5"]
    status, out, err = run(
        capsys, "hmm", "train", "--recordings", str(manifest), "-o", str(tmp_path / "m.json"), *args
    )
    assert status == 0, err
    assert "wave: 3 sequences" in out and "point: 1 sequences, 39 frames" in out
    assert len(seqs) == 8


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("name,label\nx.csv,tap\n", "a manifest starts with the header file,label[,frames]"),
        ("file,label,frames\nmine/wave/r0.csv,wave,9:2\n", "line 2: frames must be A:B with 1 ≤ A ≤ B"),
        ("file,label\nnowhere.csv,wave\n", "nowhere.csv (manifest line 2): no such recording"),
        ("file,label\n", "the manifest lists no recordings"),
        ("file,label\nmine/wave/r0.csv\n", "line 2: expected 2 fields, got 1"),
    ],
)
def test_a_bad_manifest_is_one_line(capsys, tmp_path, content, message):
    _recordings(tmp_path / "mine", n=1)
    manifest = tmp_path / "m.csv"
    manifest.write_text(content)
    status, _, err = run(
        capsys, "hmm", "train", "--recordings", str(manifest), "-o", str(tmp_path / "o.json")
    )
    assert_one_line_error(status, err, message)


def test_an_empty_folder_of_recordings_is_one_line(capsys, tmp_path):
    (tmp_path / "empty" / "wave").mkdir(parents=True)
    out = str(tmp_path / "o.json")
    status, _, err = run(capsys, "hmm", "train", "--recordings", str(tmp_path / "empty"), "-o", out)
    assert_one_line_error(status, err, "no recordings found; expected one subfolder per action")


def test_segment_reports_a_gap_and_the_candidates_it_left_out(capsys, tmp_path):
    """A log cut in the middle of its last tap, with half a second missing after frame 100 (inside the first
    tap): the gap splits the trajectory, the pieces of the cut taps are left out as partial."""
    rec = synthesize_recording("tap", 3, seed=1, noise=0.005)
    tr = rec.trajectory()
    (a, b), (c, d), (e, f) = rec.segments
    assert a < 100 < b
    cut = (e + f) // 2
    t = 1000.0 + tr.t[:cut]
    t[100:] += 0.5
    log = _write_log(tmp_path / "data.log", tr.xyz[:cut], t)
    status, out, err = run(capsys, "gestures", "segment", str(log), "--label", "tap")
    assert status == 0, err
    lines = out.splitlines()
    gap = next(line for line in lines if line.startswith("  gap of "))
    assert gap.startswith(f"  gap of {0.5 + tr.t[100] - tr.t[99]:.2f} s before frame 101 ") and gap.endswith(
        "split"
    )
    left = lines[lines.index("left out: 3") + 1 :]
    assert len(left) == 3 and all(
        line.endswith("partial: cut by the start or end of the trajectory") for line in left
    )
    assert left[1].startswith("  frames 101:") and left[2].endswith(
        f":{cut}: partial: cut by the start or end of the trajectory"
    )
    kept = [line for line in lines if line.startswith("  1. frames ")]
    start, end = map(int, kept[0].split("frames ")[1].split(" ")[0].split(":"))
    assert "segments: 1" in lines and c - 5 <= start < end <= d + 5


def test_segment_a_recording_by_name_says_its_data(capsys, source):
    status, out, err = run(capsys, "gestures", "segment", "tap1_hand", "--data", str(source.root))
    assert status == 0, err
    assert out.startswith(f"data: {source.kind} data") and "\nlog: " in out


def test_train_refuses_options_its_data_cannot_honour(capsys, tmp_path, synthetic_folder):
    import shutil

    out = str(tmp_path / "m.json")
    status, _, err = run(capsys, "hmm", "train", "--synthetic", "3", "--body-size", "1.8", "1.2", "-o", out)
    assert_one_line_error(
        status, err, "--body-size goes with --recordings (the body size of your t,x,y,z tables)"
    )
    _recordings(tmp_path / "mine", n=1)
    status, _, err = run(
        capsys, "hmm", "train", "--recordings", str(tmp_path / "mine"), "--actions", "wave,jump", "-o", out
    )
    assert_one_line_error(status, err, "--actions jump: no such label; the labels are ")
    tables = tmp_path / "tables"
    shutil.copytree(synthetic_folder, tables, ignore=shutil.ignore_patterns("gestures"))
    status, _, err = run(capsys, "hmm", "train", "--data", str(tables), "-o", out)
    assert_one_line_error(
        status, err, "the data source has no gesture recordings (", "give --data DIR with gestures/"
    )
    status, _, err = run(
        capsys, "hmm", "train", "--data", str(synthetic_folder), "--actions", "tap,wave", "-o", out
    )
    assert_one_line_error(status, err, "no training segments for wave")
    assert not (tmp_path / "m.json").exists()
