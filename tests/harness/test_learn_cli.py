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
    status, text, err = run(capsys, *argv, "-o", str(out))
    assert status == 0 and "online" in text
    assert "episode/s" not in err and "\r" not in err  # no progress bar when stderr is not a terminal
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
    status, _, err = run(
        capsys, "learning-curves", "--worlds", "moon", "--data", "synthetic", "-o", str(tmp_path)
    )
    assert_one_line_error(status, err, "--worlds: unknown 'moon'")
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
    written = {p.name for p in tmp_path.iterdir()}
    assert {
        "learning_budgets.csv",
        "learning_claims.csv",
        "learning_labels.csv",
        "learning_results.npz",
    } <= written
    study = json.loads((tmp_path / "learning_study.json").read_text())
    assert study["settings"]["episodes"] == 12 and study["update_seconds"]["median"] > 0
    assert study["made_by"]["command"].startswith("glu learning-curves --episodes 12")
    assert "seed 1 done (2 of 2)" in out
    status, _, err = run(capsys, *argv, "--part", "real-person", "--data", "synthetic", "-o", str(tmp_path))
    assert_one_line_error(status, err, "real person is in the real data only")


def _made_up_study(engine, settings, progress=None, **where):
    """Measurements of the shapes ``settings`` asks for, made up (fast), in the place of the study."""
    from glu.studies.learning import study as lc

    rng = np.random.default_rng(settings.episodes)
    learners = settings.learners()
    groups = [
        (w, a, words) for w in settings.worlds for a in settings.ambiguities for words in settings.words
    ]
    c, j = len(settings.checkpoints), 6
    out = []
    for s in settings.seeds:
        correct = rng.random((c, len(learners), j)) < 0.7
        network = rng.random((len(groups), j)) < 0.7
        labels = rng.random((len(groups), 5))
        out.append(
            lc.SeedResult(s, learners, np.array(settings.checkpoints), correct, groups, network, labels,
                          np.full(settings.episodes, 1e-3))
        )  # fmt: skip
        if progress is not None:
            progress(s)
    return out


def test_learning_curves_cut_short_leave_no_run_vouched_for_by_another_check_run(
    capsys, tmp_path, monkeypatch
):
    """glu learning-curves over a saved run, interrupted after writing its check run and before its own
    measurements (the study made up, for speed): the run is refused in one line, never read as the old run
    beside the new check run that vouches for it; a file of the user's in the folder survives."""
    from cut_short import cut_short, old_or_refused

    from glu.cli import learn_cmds
    from glu.studies.learning import saved
    from glu.studies.learning import study as lc

    monkeypatch.setattr(learn_cmds, "_engine", lambda data: (None, "synthetic (made up)"))
    monkeypatch.setattr(lc, "learning_study", _made_up_study)
    out = tmp_path / "run"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    argv = ["learning-curves", "--seeds", "0,1", "--ambiguities", "mixed", "--test-per-action", "2"]
    argv += ["--scheduler", "synchronous", "--data", "synthetic", "-o", str(out)]
    assert run(capsys, *argv, "--episodes", "12")[0] == 0
    with cut_short(saved, "atomic_write_bytes", at=2, caught=True):  # the check run's, then the run's
        status, _, err = run(capsys, *argv, "--episodes", "14")
    assert status == 130 and err == "glu learning-curves: interrupted\n"

    def commands() -> list[str]:
        return [saved.load_study(f)[2]["made_by"]["command"] for f in (out, out / saved.CHECK_FOLDER)]

    refusal = old_or_refused(commands, lambda c: all("--episodes 12 " in x for x in c))
    assert refusal is not None and "learning_study.json missing" in refusal
    assert (out / "notes.txt").read_text() == "mine\n"
    assert run(capsys, *argv, "--episodes", "14")[0] == 0
    assert all("--episodes 14 " in x for x in commands()) and (out / "notes.txt").read_text() == "mine\n"


@pytest.mark.slow  # a LocalCluster (3 s); tests/studies/test_sweep.py runs a real scheduler and worker
def test_learning_curves_on_a_local_dask_cluster_equal_the_run_here(capsys, tmp_path):
    common = ["learning-curves", "--episodes", "12", "--seeds", "0,1", "--ambiguities", "still"]
    common += ["--test-per-action", "2", "--data", "synthetic"]
    here, there = tmp_path / "here", tmp_path / "there"
    assert run(capsys, *common, "--scheduler", "synchronous", "-o", str(here))[0] == 0
    status, out, err = run(capsys, *common, "--workers", "1", "-o", str(there))
    assert status == 0, err
    for name in (
        "learning_curves.csv",
        "learning_budgets.csv",
        "learning_labels.csv",
        "learning_results.npz",
    ):
        assert (here / name).read_bytes() == (there / name).read_bytes(), name


def test_seeds_are_a_list_or_a_range_and_the_margin_an_accuracy(capsys, tmp_path):
    import argparse

    from glu.cli.learn_cmds import _seeds

    assert _seeds("0..3") == (0, 1, 2, 3) and _seeds("7..7") == (7,) and _seeds("2, 5") == (2, 5)
    for bad in ("3..1", "0..x", "1..2..3", "-1..2"):
        with pytest.raises(argparse.ArgumentTypeError, match="seeds"):
            _seeds(bad)
    status, _, err = run(
        capsys, "learning-curves", "--margin", "1", "--data", "synthetic", "-o", str(tmp_path)
    )
    assert_one_line_error(status, err, "--margin 1.0: an accuracy in (0, 1)")
    assert not any(tmp_path.iterdir())


@pytest.mark.slow  # the real person's 11 standing segments, one draw: about 30 s
def test_learning_curves_real_person_writes_its_tables(capsys, tmp_path, shared_data):
    argv = ["learning-curves", "--part", "real-person", "--draws", "0", "--scheduler", "synchronous"]
    status, out, err = run(capsys, *argv, "--data", str(shared_data), "-o", str(tmp_path))
    assert status == 0, err
    assert out.startswith("the real person: 11 standing segments × 1 draws\n")
    study = json.loads((tmp_path / "learning_real_person.json").read_text())
    assert study["settings"]["draws"] == [0]
    assert (
        study["made_by"]["command"] == "glu learning-curves --part real-person --draws 0 --data DATA -o DIR"
    )
    rows = pd.read_csv(tmp_path / "learning_real_person.csv.gz")
    summary = pd.read_csv(tmp_path / "learning_real_person_summary.csv")
    keys = ["study", "features", "learner", "words"]
    accuracy = rows.groupby(keys)["correct"].mean().rename("expected").reset_index()
    both = summary.merge(accuracy, on=keys, validate="one_to_one")
    assert len(both) == len(summary) > 0 and set(summary["segments"]) == {11} and set(summary["draws"]) == {1}
    np.testing.assert_allclose(both["accuracy"], both["expected"], rtol=0, atol=1e-12)
