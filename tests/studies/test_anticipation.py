"""Effect anticipation: per-frame HMM scores equal prefix rescoring, fusion equals single BN queries."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from glu.bn import make_engine
from glu.cli import main
from glu.data import resolve_data
from glu.errors import DataError, ModelError
from glu.fusion import fuse
from glu.gestures.recognizer import Recognizer
from glu.studies.anticipation import experiment as anticipation
from glu.studies.anticipation import recordings


@pytest.fixture(scope="module")
def setup(source, recognizer, zero_bn):
    return source, recognizer, make_engine(zero_bn)


def test_case_trajectory_is_the_logged_segment_in_model_units(setup):
    src, _, _ = setup
    traj = anticipation.case_trajectory(src, "sphere")
    raw = np.loadtxt(src.hand_log("tap_notable_seated_1"))
    assert traj.frame.tolist() == list(range(121, 215))
    np.testing.assert_allclose(traj.xyz, raw[120:214, 2:5] / 1000)


def test_run_equals_prefix_rescoring_and_single_queries(setup):
    src, rec, eng = setup
    case = anticipation.CASES["box"]
    traj = anticipation.case_trajectory(src, "box")
    run = anticipation.effect_anticipation(rec, eng, traj, case.evidence, case="box", models="bank", step=5)
    order = [rec.actions.index(a) for a in ("grasp", "tap", "touch")]
    for t in (1, 7, 50, len(traj)):
        ll = rec.loglik(traj.xyz[:t])[order]  # the whole-sequence path on the prefix, not the curve
        np.testing.assert_allclose(run.loglik[t - 1], ll, rtol=1e-9)
        np.testing.assert_allclose(run.loglik_per_frame[t - 1], ll / t, rtol=1e-9)
        np.testing.assert_allclose(run.p_hmm[t - 1], rec.p_hmm(traj.xyz[:t])[order], atol=1e-12)
    # the originals' schedule: t = 5, 10, …, the last multiple of 5 (not T)
    assert run.update_t.tolist() == list(range(5, len(traj) + 1, 5))
    assert run.update_frames.tolist() == [int(traj.frame[t - 1]) for t in range(5, len(traj) + 1, 5)]
    assert not run.update_extra.any()
    for k, f in enumerate(run.update_frames):
        i = int(np.flatnonzero(traj.frame == f)[0])
        single = fuse(eng, ["ObjVel"], case.evidence, run.p_hmm[i], "virtual")["ObjVel"]
        np.testing.assert_allclose(run.fused["ObjVel"][k], single, atol=1e-12)
    curves = run.curves()
    assert len(curves) == 3 * len(traj) and set(curves["action"]) == {"grasp", "tap", "touch"}


def test_a_bank_without_an_action_is_refused(setup):
    src, rec, eng = setup
    partial = Recognizer({a: rec.models[a] for a in ("grasp", "tap")})
    with pytest.raises(ModelError, match="no model for touch"):
        anticipation.effect_anticipation(
            partial, eng, anticipation.case_trajectory(src, "sphere"), {"Shape": "sphere"}
        )


def test_recording_of_a_run(setup, tmp_path):
    src, rec, eng = setup
    case = anticipation.CASES["sphere"]
    run = anticipation.effect_anticipation(
        rec,
        eng,
        anticipation.case_trajectory(src, "sphere"),
        case.evidence,
        case="sphere",
        models="bank",
        describe=True,
    )
    assert len(run.descriptions) == len(run.update_frames)
    assert set(run.descriptions[-1].split()) & {"ball", "sphere"}  # the grammar's words for a sphere
    path = recordings.write_anticipation(run, tmp_path / "s.rrd", "test-sphere")
    res = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "verify", str(path)], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    assert "tap" in run.scene() and "Shape=sphere" in run.scene()


def test_synthetic_case_trajectory_is_seeded():
    src = resolve_data("synthetic")
    a = anticipation.case_trajectory(src, "sphere", seed=3)
    b = anticipation.case_trajectory(src, "sphere", seed=3)
    c = anticipation.case_trajectory(src, "sphere", seed=4)
    np.testing.assert_array_equal(a.xyz, b.xyz)
    assert a.xyz.shape != c.xyz.shape or not np.array_equal(a.xyz, c.xyz)


def test_the_extra_update_at_t_equal_T_only_on_request(setup):
    src, rec, eng = setup
    traj = anticipation.case_trajectory(src, "sphere")
    T = len(traj)
    plain = anticipation.effect_anticipation(rec, eng, traj, {"Shape": "sphere"}, step=5)
    extra = anticipation.effect_anticipation(rec, eng, traj, {"Shape": "sphere"}, step=5, final_update=True)
    if T % 5:
        assert extra.update_t.tolist() == [*plain.update_t.tolist(), T]
        assert extra.update_extra.tolist() == [False] * len(plain.update_t) + [True]
        assert extra.as_dict()["updates"][-1]["extra"] is True
    else:
        assert extra.update_t.tolist() == plain.update_t.tolist() and not extra.update_extra.any()
    assert all("extra" not in u for u in plain.as_dict()["updates"])
    seven = anticipation.effect_anticipation(rec, eng, traj, {"Shape": "sphere"}, step=7)
    assert seven.update_t.tolist() == list(range(7, T + 1, 7))
    assert (anticipation.update_indices(94) + 1).tolist() == list(range(5, 91, 5))
    assert (anticipation.update_indices(146, 5, True) + 1).tolist() == [*range(5, 146, 5), 146]
    with pytest.raises(DataError, match="fewer than the update step"):
        anticipation.update_indices(3, 5)
    for step in (0, 2.5):
        with pytest.raises(
            DataError, match=f"step={step}: the update step must be a whole number of frames ≥ 1"
        ):
            anticipation.update_indices(94, step)


def test_a_case_split_by_a_repaired_gap_keeps_its_frames(synthetic_folder, tmp_path):
    """A log whose timestamps jump by 10 s after frame 60: the repair policy splits it in two pieces there
    (nothing interpolated), which are put back together; the case's frames 121–214 are the logged rows."""
    import shutil

    from glu.gestures.trajectories import RepairPolicy

    folder = tmp_path / "data"
    shutil.copytree(synthetic_folder, folder)
    log = folder / "gestures" / "tap_notable_seated_1" / "data.log"
    raw = np.loadtxt(log)
    lines = log.read_text().splitlines()
    jumped = [
        " ".join([f[0], f"{float(f[1]) + 10:.6f}", *f[2:]]) if i >= 60 else line
        for i, (line, f) in enumerate((line, line.split()) for line in lines)
    ]
    log.write_text("\n".join(jumped) + "\n")
    policy = RepairPolicy(max_interpolate=0.0, spike_threshold=np.inf)
    traj = anticipation.case_trajectory(resolve_data(folder), "sphere", policy=policy)
    assert traj.frame.tolist() == list(range(121, 215))
    np.testing.assert_allclose(traj.xyz, raw[120:214, 2:5] / 1000)


def test_run_as_dict_has_the_documented_shape(setup):
    src, rec, eng = setup
    case = anticipation.CASES["box"]
    traj = anticipation.case_trajectory(src, "box")
    run = anticipation.effect_anticipation(
        rec, eng, traj, case.evidence, case="box", targets=("ObjVel",), describe="last"
    )
    d = json.loads(json.dumps(run.as_dict(), allow_nan=False))
    assert list(d) == ["case", "frames", "loglik_per_frame", "updates", "description"]
    assert d["case"] == "box" and d["frames"] == [int(traj.frame[0]), int(traj.frame[-1])]
    assert list(d["loglik_per_frame"]) == ["grasp", "tap", "touch"]
    lpf = np.array([d["loglik_per_frame"][a] for a in ("grasp", "tap", "touch")]).T
    np.testing.assert_allclose(lpf, run.loglik / np.arange(1, len(traj) + 1)[:, None])  # index i is t = i + 1
    for u in d["updates"]:
        assert list(u) == ["t", "frame", "p_hmm", "ObjVel"] and u["frame"] == int(traj.frame[u["t"] - 1])
        assert list(u["ObjVel"]) == ["slow", "medium", "fast"]
        np.testing.assert_allclose(list(u["p_hmm"].values()), run.p_hmm[u["t"] - 1])
    assert d["description"] == run.descriptions[-1] and len(run.descriptions) == 1


def test_cli_anticipate(setup, tmp_path, capsys):
    src, rec, _ = setup
    path = tmp_path / "bank.json"
    rec.save(path)
    argv = ["anticipate", "--case", "sphere", "--models", str(path), "--data", str(src.root)]
    assert main([*argv, "--json", "--final-update"]) == 0
    out, err = capsys.readouterr()
    d = json.loads(out)
    assert set(d) == {"case", "frames", "loglik_per_frame", "updates", "description"}
    assert f"{src.kind} data" in err and "and at t = T (extra)" in err
    T = d["frames"][1] - d["frames"][0] + 1
    assert [u["t"] for u in d["updates"] if not u.get("extra")] == list(range(5, T + 1, 5))
    assert main([*argv, "--step", "10"]) == 0
    out = capsys.readouterr().out
    assert "description: " in out and "(the originals' schedule)" in out


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--models", "original", "--data", "synthetic"], "originals' HMMs"),
        (["--models", "/nonexistent.json", "--data", "synthetic"], "no such recogniser file"),
        (["--candidates", "samples", "--data", "synthetic"], "sampled sentences are not in the data"),
        (["--step", "1000"], "fewer than the update step"),
    ],
)
def test_cli_anticipate_bad_input_is_one_line(setup, tmp_path, capsys, extra, message):
    src, rec, _ = setup
    path = tmp_path / "bank.json"
    rec.save(path)
    argv = [
        "anticipate",
        "--case",
        "box",
        "--models",
        str(path),
        "--data",
        str(src.root),
        *extra,
    ]  # last wins
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_no_viewer_without_rerun_notebook_or_its_widgets(monkeypatch):
    """Live, but without rerun-notebook (no Viewer class) or with a Viewer that cannot start (ipywidgets
    missing): nothing is shown, None is returned."""
    from types import SimpleNamespace

    run = SimpleNamespace(actions=["grasp", "tap", "touch"])
    monkeypatch.setattr(recordings, "viewer_class", lambda: None)
    assert recordings.show_anticipation(run, "rid", live=True) is None

    def broken(**kwargs):
        raise ImportError("ipywidgets")

    monkeypatch.setattr(recordings, "viewer_class", lambda: broken)
    assert recordings.show_anticipation(run, "rid", live=True) is None


@pytest.mark.parametrize("n_frames", [1, 2])
def test_the_seconds_axis_needs_two_frames(n_frames):
    """The top axis maps frames to seconds by their rate: drawn for two frames (at 30 frames a second, frame
    131 is 1/3 s after frame 121), left out for one (no rate)."""
    import matplotlib.pyplot as plt
    import pandas as pd

    from glu.studies.anticipation.figures import plot_anticipation

    frames = [121, 131][:n_frames]
    actions = ["grasp", "tap", "touch"]
    curves = pd.DataFrame(
        {
            "case": "sphere",
            "models": "bank",
            "frame": np.repeat(frames, 3),
            "t": np.repeat(np.arange(1, n_frames + 1), 3),
            "seconds": np.repeat([0.0, 1 / 3][:n_frames], 3),
            "action": actions * n_frames,
            "loglik_per_frame": -1.0,
            "p_hmm": 1 / 3,
        }
    )
    preds = pd.DataFrame(
        {
            "frame": frames[-1],
            "t": n_frames,
            "node": "ObjVel",
            "value": ["slow", "medium", "fast"],
            "p": 1 / 3,
        }
    )
    fig, axes = plt.subplots(2)
    try:
        plot_anticipation(axes, curves, preds)
        secondary = axes[0].child_axes
        assert len(secondary) == n_frames - 1
        if secondary:
            forward = secondary[0]._functions[0]
            assert forward(131.0) == pytest.approx(1 / 3) and forward(121.0) == 0.0
    finally:
        plt.close(fig)


def test_every_case_with_every_bank_and_what_notebook_08_writes_of_them(setup):
    """anticipation_runs: each bank on each case, bank by bank, each run its case's evidence and its bank's
    name, as effect_anticipation alone gives it; the tables: each run's curves and predictions (with its
    description and changes), then each published comparison."""
    src, rec, eng = setup
    banks = {"a": rec, "b": rec}
    runs = anticipation.anticipation_runs(banks, eng, src, seed=3, step=10)
    assert list(runs) == [("sphere", "a"), ("box", "a"), ("sphere", "b"), ("box", "b")]
    for (case, name), run in runs.items():
        assert (run.case, run.models, run.update_t[0]) == (case, name, 10)
    one = anticipation.effect_anticipation(
        rec, eng, anticipation.case_trajectory(src, "box", seed=3), anticipation.CASES["box"].evidence,
        case="box", models="b", step=10,
    )  # fmt: skip
    np.testing.assert_array_equal(runs["box", "b"].fused["ObjVel"], one.fused["ObjVel"])
    versus = {"box": runs["box", "a"].curves().head(2)}  # stands for a published comparison
    tables = anticipation.anticipation_tables(runs, versus)
    names = [name for _, name, _ in tables]
    assert names[:2] == ["tcds_anticipation_sphere_a_curves", "tcds_anticipation_sphere_a_predictions"]
    assert len(names) == 2 * 4 + 1 and names[-1] == "tcds_anticipation_box_published"
    frame, _, extra = tables[1]
    assert extra == {
        "final_description": runs["sphere", "a"].description,
        "prediction_changes": runs["sphere", "a"].prediction_changes(),
    }
    assert frame.equals(runs["sphere", "a"].predictions()) and tables[0][2] == {}
    assert tables[-1][0] is versus["box"] and tables[-1][2] == {"reference": anticipation.PUBLISHED_REFERENCE}
    assert anticipation.published_comparisons(runs, "original") == {}  # no such bank: nothing to compare


class _Run:
    """What bank_figures reads of an anticipation run: its curves and predictions."""

    def __init__(self, case, bank, low):
        self.frames = pd.DataFrame(
            [
                {"frame": f, "t": f, "seconds": f / 30, "action": a, "loglik_per_frame": low + f + k,
                 "p_hmm": (k + 1) / 6, "case": case, "models": bank}
                for f in range(1, 11)
                for k, a in enumerate(("grasp", "tap", "touch"))
            ]
        )  # fmt: skip
        self.bars = pd.DataFrame(
            [
                {"frame": t, "t": t, "node": "ObjVel", "value": v, "p": p}
                for t in (5, 10)
                for v, p in (("slow", 0.2), ("medium", 0.3), ("fast", 0.5))
            ]
        )

    def curves(self):
        return self.frames

    def predictions(self):
        return self.bars


def _published(case):
    rows = [("loglik_per_frame", a, 5, -1.0, -1.0, 0.0, 0.01, True) for a in ("grasp", "tap", "touch")]
    rows += [
        ("ObjVel", v, 10, p, p, 0.0, 0.001, True) for v, p in (("slow", 0.2), ("medium", 0.3), ("fast", 0.5))
    ]
    cols = ["quantity", "key", "t", "ours", "paper", "difference", "resolution", "within"]
    return pd.DataFrame(rows, columns=cols)


def test_a_figure_per_bank_the_paper_beside_its_own_and_the_others_on_one_axis():
    """bank_figures: a figure per bank, in the runs' order; the paper's bank with the published bars in a
    narrow column beside each case, on its own y axis; the other banks on the one y axis their curves
    span together (shared_ylim)."""
    import matplotlib.pyplot as plt

    from glu.studies.anticipation.figures import bank_figures, shared_ylim

    lows = {"original": 0.0, "glu": -40.0, "mixsplit": 5.0}
    runs = {(c, b): _Run(c, b, low) for b, low in lows.items() for c in ("sphere", "box")}
    published = {c: _published(c) for c in ("sphere", "box")}
    figs = bank_figures(runs, published, "original")
    try:
        assert list(figs) == ["original", "glu", "mixsplit"]
        assert len(figs["original"].axes) == 6 and len(figs["glu"].axes) == len(figs["mixsplit"].axes) == 4
        span = shared_ylim([runs[c, b].curves() for b in ("glu", "mixsplit") for c in ("sphere", "box")])
        for bank in ("glu", "mixsplit"):
            tops = [figs[bank].axes[0], figs[bank].axes[2]]
            assert [ax.get_ylim() for ax in tops] == [pytest.approx(span)] * 2
            assert [ax.get_title().split(" — ")[0] for ax in tops] == [
                c.description for c in anticipation.CASES.values()
            ]
        assert figs["original"].axes[0].get_ylim() != pytest.approx(span)
    finally:
        for fig in figs.values():
            plt.close(fig)
