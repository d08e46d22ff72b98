"""`glu learn-gestures` writes a recogniser that `glu recognize` and `glu anticipate` take;
`glu learning-curves` writes the study's tables; bad input is one line with exit status 2."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from cli_run import run

from glu.cli import main
from glu.gestures.features import LOG_SCALE
from glu.gestures.recognizer import Recognizer
from glu.gestures.synthetic import synthesize_recording

SMALL = ["--states", "3", "--mix", "1", "--iter", "8"]


def assert_one_line_error(status, err, *fragments):
    assert status == 2
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for f in fragments:
        assert f in err, err


@pytest.fixture(scope="module")
def learned(tmp_path_factory):
    out = tmp_path_factory.mktemp("learned") / "r.json"
    argv = [
        "learn-gestures",
        "--episodes",
        "36",
        "--labels",
        "soft",
        "--with-words",
        "--data",
        "synthetic",
        *SMALL,
    ]
    assert main([*argv, "--seed", "3", "-o", str(out)]) == 0
    return out


def test_learn_gestures_writes_a_recogniser_that_records_how_it_learned(learned, capsys):
    rec = Recognizer.load(learned)
    assert rec.actions == ("grasp", "tap", "touch")
    assert rec.meta["labels"] == "soft" and rec.meta["episodes"] == 36 and rec.meta["words"] is True
    assert rec.meta["seed"] == 3 and 0 <= rec.meta["label_accuracy"] <= 1
    assert set(rec.reference_ranges()) == set(rec.actions)
    assert rec.models["tap"].n_states == 3 and rec.models["tap"].n_mix == 1


def test_the_learned_recogniser_recognises_and_anticipates(learned, capsys, tmp_path):
    tap = synthesize_recording("tap", 1, seed=2, noise=0.005)
    tr = tap.trajectory()
    log = tmp_path / "data.log"
    rows = [
        f"-1 {t:.6f} {x:.6f} {y:.6f} {z:.6f}"
        for t, (x, y, z) in zip(1000 + tr.t, tr.xyz * LOG_SCALE, strict=True)
    ]
    log.write_text("\n".join(rows) + "\n")
    a, b = tap.segments[0]
    status, out, _ = run(
        capsys, "recognize", str(log), "--frames", f"{a}:{b}", "--models", str(learned), "--json"
    )
    assert status == 0
    d = json.loads(out)
    rec = Recognizer.load(learned)  # the log holds the features to 6 decimals of a millimetre-scaled value
    np.testing.assert_allclose(list(d["loglik"].values()), rec.loglik(tr.frames(a, b).xyz), rtol=1e-4)
    assert abs(sum(d["posterior"].values()) - 1) < 1e-9
    status, out, _ = run(
        capsys, "anticipate", "--case", "sphere", "--models", str(learned), "--data", "synthetic", "--json"
    )
    assert status == 0 and json.loads(out)["updates"]


def test_the_threshold_reaches_the_confident_scheme(capsys, tmp_path):
    out = tmp_path / "c.json"
    argv = [
        "learn-gestures",
        "--episodes",
        "36",
        "--labels",
        "confident",
        "--with-words",
        "--data",
        "synthetic",
        *SMALL,
    ]
    assert run(capsys, *argv, "--threshold", "0.5", "-o", str(out))[0] == 0
    assert Recognizer.load(out).meta["threshold"] == 0.5


def test_online_and_true_labels(capsys, tmp_path):
    out = tmp_path / "t.json"
    argv = [
        "learn-gestures",
        "--episodes",
        "30",
        "--labels",
        "true",
        "--online",
        "--data",
        "synthetic",
        *SMALL,
    ]
    status, text, _ = run(capsys, *argv, "-o", str(out))
    assert status == 0 and "online" in text
    assert Recognizer.load(out).meta["learning"] == "online"


def test_bad_input_is_one_line(capsys, tmp_path):
    out = str(tmp_path / "x.json")
    status, _, err = run(capsys, "learn-gestures", "--episodes", "10", "--labels", "guess", "-o", out)
    assert status == 2 and "invalid choice" in err and "Traceback" not in err
    status, _, err = run(capsys, "learn-gestures", "--episodes", "0", "--labels", "soft", "-o", out)
    assert status == 2 and "≥ 1" in err
    status, _, err = run(
        capsys,
        "learn-gestures",
        "--episodes",
        "12",
        "--labels",
        "soft",
        "--threshold",
        "2",
        "--data",
        "synthetic",
        "-o",
        out,
    )
    assert_one_line_error(status, err, "--threshold 2")
    status, _, err = run(
        capsys,
        "learn-gestures",
        "--episodes",
        "12",
        "--labels",
        "confident",
        "--ambiguity",
        "still",
        "--data",
        "synthetic",
        *SMALL,
        "-o",
        out,
    )
    assert_one_line_error(status, err, "label weight")
    status, _, err = run(
        capsys, "learning-curves", "--ambiguities", "foggy", "--data", "synthetic", "-o", str(tmp_path)
    )
    assert_one_line_error(status, err, "unknown 'foggy'")
    status, _, err = run(capsys, "learning-curves", "--seeds", "1,1", "-o", str(tmp_path))
    assert status == 2 and "distinct seeds" in err


def test_learning_curves_writes_the_study_tables(capsys, tmp_path):
    argv = [
        "learning-curves",
        "--episodes",
        "12",
        "--seeds",
        "0,1",
        "--ambiguities",
        "mixed",
        "--test-per-action",
        "2",
    ]
    status, out, _ = run(
        capsys, *argv, "--scheduler", "synchronous", "--data", "synthetic", "-o", str(tmp_path)
    )
    assert status == 0, out
    curves = pd.read_csv(tmp_path / "learning_curves.csv")
    assert set(curves["episodes"]) == {10, 12} and set(curves["seeds"]) == {2}
    assert {"learning_match.csv", "learning_labels.csv", "learning_study.json"} <= {
        p.name for p in tmp_path.iterdir()
    }
    study = json.loads((tmp_path / "learning_study.json").read_text())
    assert study["settings"]["episodes"] == 12 and study["update_seconds"]["median"] > 0


@pytest.mark.slow  # a LocalCluster (3 s); tests/studies/test_sweep.py runs a real scheduler and worker
def test_learning_curves_on_a_local_dask_cluster_equal_the_run_here(capsys, tmp_path):
    common = ["learning-curves", "--episodes", "12", "--seeds", "0,1", "--ambiguities", "still"]
    common += ["--test-per-action", "2", "--data", "synthetic"]
    here, there = tmp_path / "here", tmp_path / "there"
    assert run(capsys, *common, "--scheduler", "synchronous", "-o", str(here))[0] == 0
    status, out, err = run(capsys, *common, "--workers", "1", "-o", str(there))
    assert status == 0, err
    for name in ("learning_curves.csv", "learning_match.csv", "learning_labels.csv"):
        assert (here / name).read_bytes() == (there / name).read_bytes(), name


def test_a_long_learning_says_it_is_still_running(capsys):
    """glu learn-gestures' heartbeat: a line on stderr while the block runs, the time it took at the end."""
    import time

    from glu.cli.learn_cmds import heartbeat

    seen = ""
    with heartbeat("learning", 0.01, enabled=True):
        for _ in range(1000):  # until the first beat (a wait for an event, not a timed assertion)
            seen += capsys.readouterr().err
            if "learning:" in seen and "s so far" in seen:
                break
            time.sleep(0.01)
    seen += capsys.readouterr().err
    assert "s so far" in seen and seen.rstrip().splitlines()[-1].startswith("  learning: done in")
