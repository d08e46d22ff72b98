"""Rerun recordings: written headless in strict mode, read back with pyarrow, compared with `rrd compare`."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from glu.studies.anticipation.recordings import write_anticipation_recording

ACTIONS = ["grasp", "tap", "touch"]


@pytest.fixture(autouse=True)
def strict():
    rr.set_strict_mode(True)
    yield
    rr.set_strict_mode(False)


def _fake_run(seed: int, n: int = 40):
    rng = np.random.default_rng(seed)
    xyz = np.cumsum(rng.normal(size=(n, 3)) * 0.01, axis=0)
    frames = np.arange(100, 100 + n)
    seconds = np.arange(n) / 30.0
    ll = np.cumsum(rng.normal(size=(n, 3)), axis=0) / np.arange(1, n + 1)[:, None]
    p = np.exp(ll - ll.max(1, keepdims=True))
    p /= p.sum(1, keepdims=True)
    upd = frames[4::5]
    objvel = rng.dirichlet(np.ones(3), size=len(upd))
    return dict(
        xyz=xyz,
        seconds=seconds,
        frames=frames,
        actions=ACTIONS,
        loglik_per_frame=ll,
        p_hmm=p,
        update_frames=upd,
        fused={"ObjVel": objvel, "Action": p[4::5]},
        values={"ObjVel": ["slow", "medium", "fast"], "Action": ACTIONS},
        scene="# tap on a small sphere",
        descriptions=[f"the robot taps the ball {i}" for i in range(len(upd))],
    )


def _static(path, entity, component):
    """The static value of a component (its last row), as a Python list."""
    stream = RrdReader(str(path)).stream().filter(content=entity, is_static=True, components=component)
    rows = [row for c in stream for row in c.to_record_batch().column(component).to_pylist()]
    return rows[-1]


def _column(path, entity, component, index="frame"):
    stream = RrdReader(str(path)).stream().filter(content=entity, is_static=False, components=component)
    batches = [c.to_record_batch().select([index, component]) for c in stream]
    return pa.Table.from_batches(batches).sort_by(index)


def test_recording_content_reads_back(tmp_path):
    run = _fake_run(0)
    path = write_anticipation_recording(tmp_path / "a.rrd", "test-a", **run)
    res = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "verify", str(path)], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    tap = _column(path, "/hmm/p_hmm/tap", "Scalars:scalars")
    assert tap.column("frame").to_pylist() == run["frames"].tolist()
    got = np.array([v[0] for v in tap.column("Scalars:scalars").to_pylist()])
    np.testing.assert_allclose(got, run["p_hmm"][:, 1])
    for j, value in enumerate(["slow", "medium", "fast"]):  # one named series per value, at the updates
        series = _column(path, f"/fusion/ObjVel/{value}", "Scalars:scalars")
        assert series.column("frame").to_pylist() == run["update_frames"].tolist()
        got = [v[0] for v in series.column("Scalars:scalars").to_pylist()]
        np.testing.assert_allclose(got, run["fused"]["ObjVel"][:, j], rtol=1e-12)
        for kind in ("SeriesLines", "SeriesPoints"):  # the legend's name is the value's, not the path
            assert _static(path, f"/fusion/ObjVel/{value}", f"{kind}:names") == [value]
    assert not list(RrdReader(str(path)).stream().filter(content="/fusion/**", components="BarChart:values"))
    pos = _column(path, "/hand/position", "Points3D:positions")
    np.testing.assert_allclose(
        np.array(pos.column("Points3D:positions").to_pylist()[-1][0]), run["xyz"][-1], rtol=1e-6
    )
    texts = _column(path, "/description", "TextLog:text")
    assert texts.column("TextLog:text").to_pylist()[0] == ["the robot taps the ball 0"]
    assert len(RrdReader(str(path)).blueprints()) == 1


def test_the_scene_panel_is_markdown_and_ends_with_the_note_as_plain_text(tmp_path):
    note = "real data: origin@1234 · 08_tcds_figures with n_iter=5 <b>"
    path = write_anticipation_recording(tmp_path / "a.rrd", "test-note", note=note, **_fake_run(0))
    text = _static(path, "/scene", "TextDocument:text")[0]
    assert text.startswith("# tap on a small sphere\n\n---\n\n")
    assert "<small>" not in text and "<b>" not in text  # the panel renders Markdown, not HTML
    assert text.endswith(r"real data: origin@1234 · 08\_tcds\_figures with n\_iter=5 \<b\>")


def test_same_data_compares_equal_and_different_data_does_not(tmp_path):
    a = write_anticipation_recording(tmp_path / "a.rrd", "rid-a", **_fake_run(1))
    b = write_anticipation_recording(tmp_path / "b.rrd", "rid-b", **_fake_run(1))
    c = write_anticipation_recording(tmp_path / "c.rrd", "rid-c", **_fake_run(2))
    cmp = [sys.executable, "-m", "rerun", "rrd", "compare"]
    assert subprocess.run([*cmp, str(a), str(b)], capture_output=True).returncode == 0
    assert subprocess.run([*cmp, str(a), str(c)], capture_output=True).returncode != 0
