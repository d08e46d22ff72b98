"""Every notebook runs headless with papermill in quick mode, writes its figures, and does so deterministically."""

from __future__ import annotations

import filecmp
import json
import subprocess
import sys
from pathlib import Path

import jupytext
import papermill as pm
import pytest

from glu.reproduce import NotebookError, list_notebooks, reproduce

EXPECTED_FIGURES = {
    "01_gesture_features": ["gesture_segmentation"],
    "02_hmm_training": ["hmm_synthetic_accuracy"],
    "03_bn_learning": ["bn_structure", "unseen_rows_comparison"],
    "04_fusion_hard": ["fusion_hard_on_gestures"],
    "05_fusion_soft": ["fusion_soft_rules", "fusion_soft_sweep"],
    "06_fusion_product": ["fusion_product_action", "fusion_product_thresholds"],
    "07_glu2017_figures": [
        "glu2017_effect_prediction",
        "glu2017_word_change_text",
        "glu2017_word_change_code",
    ],
    "08_tcds_figures": [
        "tcds_action_vs_soft_evidence",
        "tcds_effect_vs_soft_evidence",
        "tcds_anticipation_glu",
    ],
    "09_verbal_descriptions": ["verbal_and_but", "verbal_yellow_sphere_nbest", "verbal_sampling_vs_exact"],
}
EXPECTED_RECORDINGS = {"08_tcds_figures": ["tcds_anticipation_sphere_glu", "tcds_anticipation_box_glu"]}
COMMON_PARAMETERS = {"data", "seed", "quick", "out_dir"}
NOTEBOOKS = [p.stem for p in list_notebooks()]


def _silent(_msg: str) -> None:
    pass


@pytest.fixture(scope="session")
def quick_runs(tmp_path_factory):
    """Two complete quick runs on synthetic data with the same parameters."""
    outs = []
    for k in range(2):
        out = tmp_path_factory.mktemp(f"run{k}")
        summary = reproduce(data="synthetic", quick=True, out=out, jobs=2, log=_silent)
        outs.append((out, summary))
    return outs


def test_every_notebook_is_known_and_parameterised():
    assert NOTEBOOKS, "no notebooks found"
    for path in list_notebooks():
        assert path.stem in EXPECTED_FIGURES, f"{path.stem}: add its figures to EXPECTED_FIGURES"
        params = pm.inspect_notebook(jupytext.read(path))
        assert COMMON_PARAMETERS <= set(params), (
            f"{path.stem} lacks parameters {COMMON_PARAMETERS - set(params)}"
        )
        assert path.read_text().count('tags=["parameters"]') == 1
        for name, p in params.items():  # what `papermill --help-notebook` lists: a type and a comment each
            assert p["inferred_type_name"] not in ("None", "Unknown type"), f"{path.stem}: {name} has no type"
            assert p["help"], f"{path.stem}: {name} has no comment"


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_quick_run_writes_its_figures(quick_runs, name):
    out, summary = quick_runs[0]
    status = {n["name"]: n["status"] for n in summary["notebooks"]}
    assert status[name] == "ok"
    for fig in EXPECTED_FIGURES[name]:
        for ext in ("png", "svg"):
            f = out / "figures" / f"{fig}.{ext}"
            assert f.is_file() and f.stat().st_size > 1000, f
    assert (out / "notebooks" / f"{name}.ipynb").is_file()
    for rec in EXPECTED_RECORDINGS.get(name, []):
        f = out / "recordings" / f"{rec}.rrd"
        res = subprocess.run(
            [sys.executable, "-m", "rerun", "rrd", "verify", str(f)], capture_output=True, text=True
        )
        assert res.returncode == 0, f"{rec}: {res.stderr}"
    svg = (out / "figures" / f"{EXPECTED_FIGURES[name][0]}.svg").read_text()
    assert "synthetic data" in svg  # every figure says which data it came from


def test_the_trained_recogniser_is_published_to_models(quick_runs):
    out, _ = quick_runs[0]
    from glu.gestures.recognizer import Recognizer

    rec = Recognizer.load(out / "models" / "recognizer_synthetic.json")
    assert set(rec.actions) == {"grasp", "tap", "touch"}


def test_summary_has_every_number_and_the_provenance(quick_runs):
    out, summary = quick_runs[0]
    doc = json.loads((out / "results" / "summary.json").read_text())
    assert doc["data_source"].startswith("synthetic data")
    assert doc["versions"]["numpy"] and doc["versions"]["glu"]
    assert "glu2017_effect_prediction" in doc["tables"]
    rows = doc["tables"]["glu2017_effect_prediction"]["rows"]
    assert len(rows) == 6 and abs(sum(r["p"] for r in rows) - 2) < 1e-9
    csv = (out / "results" / "summary.csv").read_text().splitlines()
    assert csv[0] == "table,row,column,value" and len(csv) > 100


def test_two_runs_are_identical(quick_runs):
    (a, sa), (b, sb) = quick_runs
    figs = sorted((a / "figures").iterdir())
    assert figs
    for f in figs:
        assert filecmp.cmp(f, b / "figures" / f.name, shallow=False), f"{f.name} differs between runs"
    for f in sorted((a / "results").glob("*.csv")):
        if f.name != "summary.csv":
            assert f.read_bytes() == (b / "results" / f.name).read_bytes(), f.name
    for f in sorted((a / "recordings").glob("*.rrd")) if (a / "recordings").exists() else []:
        res = subprocess.run([sys.executable, "-m", "rerun", "rrd", "compare", str(f), str(b / "recordings" / f.name)],
                             capture_output=True, text=True)  # fmt: skip
        assert res.returncode == 0, f"{f.name}: {res.stdout}{res.stderr}"


_OK = """# %% tags=["parameters"]
data = None
seed = 0
quick = False
out_dir = None

# %%
from pathlib import Path
Path(out_dir, "figures").mkdir(parents=True, exist_ok=True)
Path(out_dir, "figures", "new.txt").write_text("new")
"""
_FAIL = (
    _OK
    + """
# %%
x = 1

# %%
raise RuntimeError("deliberate failure")
"""
)


def test_a_failing_notebook_stops_with_a_clear_message_and_keeps_earlier_outputs(tmp_path):
    nbs = tmp_path / "nbs"
    nbs.mkdir()
    (nbs / "01_ok.py").write_text(_OK)
    (nbs / "02_fails.py").write_text(_FAIL.replace('"new"', '"newer"'))
    out = tmp_path / "out"
    (out / "figures").mkdir(parents=True)
    (out / "figures" / "earlier.png").write_bytes(b"earlier output")
    (out / "results").mkdir()
    (out / "results" / "summary.json").write_text("{}")
    with pytest.raises(NotebookError) as e:
        reproduce(data="synthetic", out=out, jobs=1, log=_silent, notebooks_dir=nbs)
    msg = str(e.value)
    assert "notebook 02_fails failed in cell" in msg and "RuntimeError: deliberate failure" in msg
    assert (out / "notebooks" / "02_fails.failed.ipynb").is_file()
    assert (out / "figures" / "earlier.png").read_bytes() == b"earlier output"
    assert (out / "figures" / "new.txt").read_text() == "new"  # the notebook that succeeded landed
    assert (out / "results" / "summary.json").read_text() == "{}"  # no summary of a failed run
    assert not (out / ".glu-staging").exists()
    with pytest.raises(NotebookError, match="no notebook matches 'nope'"):
        reproduce(data="synthetic", out=out, only=["nope"], log=_silent, notebooks_dir=nbs)


_TABLE = (
    _OK
    + """
# %%
import pandas as pd
from glu.outputs import open_outputs
out = open_outputs(NAME, data, out_dir)
out.table(pd.DataFrame({"x": [seed]}), NAME)
"""
)


def test_a_partial_run_updates_the_summary_of_the_same_data(tmp_path):
    nbs = tmp_path / "nbs"
    nbs.mkdir()
    for name in ("01_a", "02_b"):
        (nbs / f"{name}.py").write_text(_TABLE.replace("NAME", repr(name)))
    out = tmp_path / "out"
    full = reproduce(data="synthetic", out=out, log=_silent, notebooks_dir=nbs, seed=1)
    assert set(full["tables"]) == {"01_a", "02_b"} and full["ran"] == ["01_a", "02_b"]
    part = reproduce(data="synthetic", out=out, log=_silent, notebooks_dir=nbs, only=["02"], seed=5)
    assert part["ran"] == ["02_b"] and set(part["tables"]) == {"01_a", "02_b"}
    assert part["tables"]["01_a"]["rows"] == [{"x": 1}] and part["tables"]["02_b"]["rows"] == [{"x": 5}]
    other = reproduce(data="synthetic", quick=True, out=out, log=_silent, notebooks_dir=nbs, only=["02"])
    assert set(other["tables"]) == {"02_b"}  # another mode: a fresh summary, nothing mixed


def test_notebook_sources_have_no_outputs():
    for path in list_notebooks():
        nb = jupytext.read(path)
        assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")
        assert Path(path).suffix == ".py"
