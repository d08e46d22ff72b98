"""Effect anticipation: per-frame HMM scores equal prefix rescoring, fusion equals single BN queries."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from glu import recording
from glu.bn import InferenceEngine
from glu.data import resolve_data
from glu.errors import ModelError
from glu.experiments import anticipation
from glu.fusion import fuse
from glu.gestures.recognizer import Recognizer


@pytest.fixture(scope="module")
def setup(source, recognizer, zero_bn):
    return source, recognizer, InferenceEngine(zero_bn)


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
    expected_frames = [traj.frame[i] for i in range(4, len(traj), 5)] + [traj.frame[-1]]
    assert run.update_frames.tolist() == sorted(set(expected_frames))
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
    run = anticipation.effect_anticipation(rec, eng, anticipation.case_trajectory(src, "sphere"), case.evidence,
                                           case="sphere", models="bank", describe=True)  # fmt: skip
    assert len(run.descriptions) == len(run.update_frames)
    assert set(run.descriptions[-1].split()) & {"ball", "sphere"}  # the grammar's words for a sphere
    path = recording.write_anticipation(run, tmp_path / "s.rrd", "test-sphere")
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
