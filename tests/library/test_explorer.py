"""The evidence explorer: its numbers are the network's, its widgets update them, headless it is a table."""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pytest

from glu.bn import make_engine
from glu.explorer import NOT_OBSERVED, evidence_explorer, explore

ACTIONS = ("grasp", "tap", "touch")


@pytest.fixture(scope="module")
def engine(zero_bn):
    return make_engine(zero_bn)


def _p(exploration, node):
    d = exploration.posteriors
    return d[d["node"] == node]["p"].to_numpy()


def test_hard_evidence_gives_the_networks_marginals(engine):
    ex = explore(engine, ["ObjVel", "Action"], {"Shape": "sphere", "Size": "small"})
    ref = engine.query(["ObjVel", "Action"], {"Shape": "sphere", "Size": "small"})
    np.testing.assert_allclose(_p(ex, "ObjVel"), ref["ObjVel"], atol=1e-12)
    np.testing.assert_allclose(_p(ex, "Action"), ref["Action"], atol=1e-12)
    assert len(ex.descriptions) == 3 and ex.evidence_text == "Shape=sphere, Size=small"


def test_gesture_evidence_is_the_virtual_evidence_closed_form(engine):
    """p(X | e, G) ∝ Σ_a p(X, a | e) q(a): built from hard-evidence queries, independently of fuse()."""
    q = np.array([0.2, 0.5, 0.3])
    ev = {"Shape": "sphere"}
    p_a = engine.query(["Action"], ev)["Action"]
    num = sum(
        p_a[i] * q[i] * engine.query(["ObjVel"], {**ev, "Action": a})["ObjVel"] for i, a in enumerate(ACTIONS)
    )
    ex = explore(engine, ["ObjVel"], ev, q, "virtual")
    np.testing.assert_allclose(_p(ex, "ObjVel"), num / num.sum(), atol=1e-12)
    jeff = sum(q[i] * engine.query(["ObjVel"], {**ev, "Action": a})["ObjVel"] for i, a in enumerate(ACTIONS))
    np.testing.assert_allclose(_p(explore(engine, ["ObjVel"], ev, q, "jeffrey"), "ObjVel"), jeff, atol=1e-12)


def test_observed_targets_are_left_out_and_gesture_ignored_when_action_is_observed(engine):
    ex = explore(engine, ["ObjVel", "Action"], {"Action": "tap"}, [0.1, 0.1, 0.8])
    assert set(ex.posteriors["node"]) == {"ObjVel"}
    np.testing.assert_allclose(_p(ex, "ObjVel"), engine.query(["ObjVel"], {"Action": "tap"})["ObjVel"])


@pytest.mark.parametrize("live", [False, True], ids=["headless", "live-without-ipywidgets"])
def test_headless_or_without_ipywidgets_it_is_a_static_table(engine, live, monkeypatch):
    monkeypatch.setitem(sys.modules, "ipywidgets", None)  # `import ipywidgets` fails
    table = evidence_explorer(engine, evidence={"Shape": "box"}, live=live)
    assert isinstance(table, pd.DataFrame)
    np.testing.assert_allclose(
        table.loc["ObjVel", ["slow", "medium", "fast"]].to_numpy(dtype=float),
        engine.query(["ObjVel"], {"Shape": "box"})["ObjVel"],
        atol=1e-12,
    )


def test_live_the_widgets_update_the_answer(engine):
    pytest.importorskip("ipywidgets")
    box = evidence_explorer(engine, live=True)
    drops = box.controls["evidence"]
    drops["Shape"].value = "sphere"  # each change recomputes (the widgets' observers)
    drops["Size"].value = "small"
    box.controls["gesture"].value = True
    for slider, v in zip(box.controls["sliders"], [0.1, 0.8, 0.1], strict=True):
        slider.value = v
    expected = explore(engine, ["ObjVel", "Action"], {"Shape": "sphere", "Size": "small"}, [0.1, 0.8, 0.1])
    assert box.view.value == expected.to_html()
    drops["Shape"].value = NOT_OBSERVED
    assert "Shape" not in box.view.value.split("</p>")[0]
    word = sorted(engine.bn.zero_rows())[0]  # evidence that the original's all-zero rows make impossible
    row = np.argwhere(engine.bn.cpts[word].sum(axis=-1) == 0)[0]
    box.controls["gesture"].value = False
    for parent, i in zip(engine.bn.parents[word], row, strict=True):
        drops[parent].value = engine.bn.schema.values_of(parent)[i]
    assert "cannot answer" in box.view.value and "impossible evidence" in box.view.value


def test_the_rerun_viewer_shows_only_when_live(tmp_path, monkeypatch):
    pytest.importorskip("rerun_notebook")
    from glu.studies.anticipation.recordings import show_anticipation

    # a URL the viewer would load its files from (never fetched here): no asset server in this process; the
    # files served offline are tests/harness/test_viewer_offline.py's business
    monkeypatch.setenv("RERUN_NOTEBOOK_ASSET", "http://127.0.0.1:9/widget.js")

    class _Run:  # the fields a run has, small
        actions = list(ACTIONS)
        xyz = np.zeros((10, 3))
        seconds = np.arange(10) / 30
        frames = np.arange(1, 11)
        loglik_per_frame = np.zeros((10, 3))
        p_hmm = np.full((10, 3), 1 / 3)
        update_frames = np.array([5, 10])
        fused = {"ObjVel": np.full((2, 3), 1 / 3)}
        values = {"ObjVel": ["slow", "medium", "fast"]}
        descriptions = ["a", "b"]
        data_source = "synthetic data"

        def scene(self):
            return "# test"

    assert show_anticipation(_Run(), "rid", live=False) is None
    viewer = show_anticipation(_Run(), "rid", live=True)
    from rerun.notebook import Viewer

    assert isinstance(viewer, Viewer)
