"""Every notebook runs headless with papermill in quick mode, writes its figures, and does so
deterministically."""

from __future__ import annotations

import filecmp
import json
import subprocess
import sys
from pathlib import Path

import jupytext
import papermill as pm
import pytest
from browser import browser, needs_browser, search, walk_site

from glu.plots.overlap import CHECK_ENV
from glu.run.manifest import read_manifest
from glu.run.parameters import read_spec
from glu.run.provenance import read_provenance
from glu.run.reproduce import NotebookError, list_notebooks, reproduce
from glu.run.site_api import api_modules

COMMON_PARAMETERS = {"data", "seed", "out_dir"}
NOTEBOOKS = [p.stem for p in list_notebooks()]
MANIFESTS = {p.stem: read_manifest(p) for p in list_notebooks()}
"""What each notebook declares it writes (its header): the tests check the runs against it."""


def _silent(_msg: str) -> None:
    pass


AGAIN = ["01", "02", "08"]
"""Notebooks run a second time to check determinism: segmentation, HMM training (random initialisation,
EM), and the recordings."""


FIGURE_CHECKS: dict[Path, Path] = {}
"""Each quick run's folder → where it wrote the readability check of every figure (glu.plots.overlap)."""


@pytest.fixture(scope="session")
def quick_runs(tmp_path_factory):
    """A complete quick run on synthetic data, and a second run of :data:`AGAIN` with the same parameters.

    Both check every figure they save for overlapping text (``GLU_FIGURE_CHECK``, see
    :data:`FIGURE_CHECKS`); the files are the same with and without the check.
    """
    outs = []
    for k, only in enumerate((None, AGAIN)):
        out = tmp_path_factory.mktemp(f"run{k}")
        FIGURE_CHECKS[out] = tmp_path_factory.mktemp(f"run{k}-figure-check")
        with pytest.MonkeyPatch.context() as env:
            env.setenv(CHECK_ENV, str(FIGURE_CHECKS[out]))
            summary = reproduce(
                data="synthetic", quick=True, out=out, jobs=2, log=_silent, only=only, site=only is None
            )
        outs.append((out, summary))
    return outs


def test_every_notebook_is_known_and_parameterised():
    assert NOTEBOOKS, "no notebooks found"
    for path in list_notebooks():
        manifest = MANIFESTS[path.stem]
        assert manifest.about and manifest.figures, f"{path.stem}: its manifest names no figures"
        assert (
            "quick" not in pm.inspect_notebook(jupytext.read(path)) and "if quick" not in path.read_text()
        ), f"{path.stem}: a quick run is its manifest's preset, not a `quick` flag"
        params = pm.inspect_notebook(jupytext.read(path))
        assert COMMON_PARAMETERS <= set(params), (
            f"{path.stem} lacks parameters {COMMON_PARAMETERS - set(params)}"
        )
        assert path.read_text().count('tags=["parameters"]') == 1
        assert set(manifest.quick) <= set(params) - COMMON_PARAMETERS, f"{path.stem}: quick preset names"
        for name, p in params.items():  # what `papermill --help-notebook` lists: a type and a comment each
            assert p["inferred_type_name"] not in ("None", "Unknown type"), f"{path.stem}: {name} has no type"
            assert p["help"], f"{path.stem}: {name} has no comment"


def test_the_notebooks_folder_tracks_only_the_notebooks():
    """Nothing a run writes is committed beside the notebooks (three empty figure-check reports once were,
    in notebooks/1/)."""
    root = list_notebooks()[0].parent
    if not (root.parent / ".git").exists():
        pytest.skip("not a git checkout")
    tracked = subprocess.run(
        ["git", "ls-files", "."], cwd=root, capture_output=True, text=True, check=True
    ).stdout.split()
    assert sorted(tracked) == sorted([*(p.name for p in list_notebooks()), "__init__.py"])


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_quick_run_writes_its_figures(quick_runs, name):
    out, summary = quick_runs[0]
    status = {n["name"]: n["status"] for n in summary["notebooks"]}
    assert status[name] == "ok"
    manifest = MANIFESTS[name]
    for fig in manifest.outputs("figures", real=False):
        for ext in ("png", "svg"):
            f = out / "figures" / f"{fig}.{ext}"
            assert f.is_file() and f.stat().st_size > 1000, f
    assert (out / "notebooks" / f"{name}.ipynb").is_file()
    for rec in manifest.outputs("recordings", real=False):
        f = out / "recordings" / f"{rec}.rrd"
        res = subprocess.run(
            [sys.executable, "-m", "rerun", "rrd", "verify", str(f)], capture_output=True, text=True
        )
        assert res.returncode == 0, f"{rec}: {res.stderr}"
    svg = (out / "figures" / f"{manifest.outputs('figures', real=False)[0]}.svg").read_text()
    assert "synthetic data" in svg  # every figure says which data it came from


def test_no_figure_has_overlapping_text_or_a_legend_on_data(quick_runs):
    """Every figure of the quick run passes glu.plots.overlap: no text on text or on data, no series told
    apart by colour alone (tests/library/test_figure_overlap.py tests the check)."""
    out, _ = quick_runs[0]
    pngs = sorted((out / "figures").glob("*.png"))
    expected = {f for m in MANIFESTS.values() for f in m.figures if f not in m.real_only}
    assert expected <= {p.stem for p in pngs}
    problems = {}
    for png in pngs:
        report = FIGURE_CHECKS[out] / f"{png.stem}.txt"
        assert report.is_file(), f"{png.name} was not checked"
        if report.read_text().splitlines():
            problems[png.stem] = report.read_text().splitlines()
    assert not problems, "\n".join(f"{name}: {p}" for name, ps in problems.items() for p in ps)


def test_the_trained_recogniser_is_published_to_models(quick_runs):
    out, _ = quick_runs[0]
    from glu.gestures.recognizer import Recognizer

    rec = Recognizer.load(out / "models" / "recognizer.json")
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
    figs = sorted((b / "figures").iterdir())  # the second run's (a subset of the first's)
    assert len([f for f in figs if f.suffix == ".png"]) >= 4
    for f in figs:
        assert filecmp.cmp(f, a / "figures" / f.name, shallow=False), f"{f.name} differs between runs"
    tables = [f for f in sorted((b / "results").glob("*.csv")) if f.name != "summary.csv"]
    assert tables
    for f in tables:
        assert f.read_bytes() == (a / "results" / f.name).read_bytes(), f.name
    recordings = sorted((b / "recordings").glob("*.rrd"))
    assert recordings
    for f in recordings:
        res = subprocess.run(
            [sys.executable, "-m", "rerun", "rrd", "compare", str(f), str(a / "recordings" / f.name)],
            capture_output=True,
            text=True,
        )
        assert res.returncode == 0, f"{f.name}: {res.stdout}{res.stderr}"


_OK = """# ---
# jupyter:
#   glu:
#     about: a test notebook
# ---

# %% tags=["parameters"]
data: str = None  # data folder
seed: int = 0  # seed
out_dir: str = None  # outputs

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


def test_a_failing_notebook_stops_the_run_and_nothing_is_published(tmp_path):
    nbs = tmp_path / "nbs"
    nbs.mkdir()
    (nbs / "01_ok.py").write_text(_OK.replace('"new"', 'f"new {seed}"'))
    (nbs / "02_fails.py").write_text(_FAIL.replace('"new"', '"newer"'))
    out = tmp_path / "out"
    earlier = reproduce(
        data="synthetic", out=out, jobs=1, log=_silent, notebooks_dir=nbs, only=["01"], seed=1, site=False
    )
    summary = (out / "results" / "summary.json").read_bytes()
    with pytest.raises(NotebookError) as e:
        reproduce(data="synthetic", out=out, jobs=1, log=_silent, notebooks_dir=nbs, seed=2)
    msg = str(e.value)
    assert "notebook 02_fails failed in cell" in msg and "RuntimeError: deliberate failure" in msg
    assert (out / ".glu-runs" / "failed" / "02_fails.failed.ipynb").is_file()
    assert "02_fails.failed.ipynb" in msg
    assert (out / "figures" / "new.txt").read_text() == "new 1"  # all or nothing: the earlier run stays
    assert "nothing was published" in msg
    assert (out / "results" / "summary.json").read_bytes() == summary  # no summary of a failed run
    assert earlier["ran"] == ["01_ok"]
    assert len([d for d in (out / ".glu-runs").iterdir() if d.name.startswith("r")]) == 1  # no staging left
    with pytest.raises(NotebookError, match="no notebook matches 'nope'"):
        reproduce(data="synthetic", out=out, only=["nope"], log=_silent, notebooks_dir=nbs)
    with pytest.raises(NotebookError, match="no notebook matches ''"):
        reproduce(data="synthetic", out=out, only=[""], log=_silent, notebooks_dir=nbs)


_TABLE = """# ---
# jupyter:
#   glu:
#     about: a test notebook
#     tables: [NAME]
# ---

# %% tags=["parameters"]
data: str = None  # data folder
seed: int = 0  # seed
out_dir: str = None  # outputs

# %%
import pandas as pd
from glu.run import start
out = start(NAME, globals())
out.table(pd.DataFrame({"x": [seed]}), NAME)
"""


@pytest.mark.slow  # a third quick run (15 s): the default suite keeps the complete run and its repeat
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


def test_every_executed_notebook_shows_every_figure_it_wrote(quick_runs):
    """A reader of an executed notebook sees each figure inline: the very PNG that was saved."""
    import base64

    out, summary = quick_runs[0]
    written: dict[str, set[str]] = {}
    for fname, nb in summary["figures_by_notebook"].items():
        if fname.endswith(".png"):
            written.setdefault(nb, set()).add(fname)
    assert written, "no figures were written"
    for name in NOTEBOOKS:
        nb = json.loads((out / "notebooks" / f"{name}.ipynb").read_text())
        shown = {}
        for cell in nb["cells"]:
            for o in cell.get("outputs", []):
                if "image/png" in o.get("data", {}):
                    shown[o["metadata"]["glu"]["figure"]] = base64.b64decode(o["data"]["image/png"])
        assert set(shown) == written.get(name, set()), f"{name}: figures written vs shown differ"
        for fname, png in shown.items():
            assert png == (out / "figures" / fname).read_bytes(), f"{name}: {fname} shown is not the file"


def test_every_table_a_notebook_shows_is_formatted_for_reading(quick_runs):
    """A cell that ends with a DataFrame shows glu.tidy.html_table's form of it (tests/library/
    test_tidy_display.py checks that form): no pandas default table in any executed notebook."""
    out, _ = quick_runs[0]
    shown = 0
    for name in NOTEBOOKS:
        nb = json.loads((out / "notebooks" / f"{name}.ipynb").read_text())
        for cell in nb["cells"]:
            for o in cell.get("outputs", []):
                html = "".join(o.get("data", {}).get("text/html", ""))
                if "<table" in html:
                    shown += 1
                    assert 'class="dataframe glu-table"' in html, f"{name}: a table not formatted for reading"
    assert shown >= 5


def test_every_executed_notebook_names_its_data_first(quick_runs):
    out, _ = quick_runs[0]
    for name in NOTEBOOKS:
        nb = json.loads((out / "notebooks" / f"{name}.ipynb").read_text())
        texts = [
            "".join(o["data"].get("text/markdown", ""))
            for c in nb["cells"]
            for o in c.get("outputs", [])
            if o.get("output_type") == "display_data"
        ]
        assert texts and texts[0].startswith(f"**{name}** · synthetic data (seed 0, 1270 experiments)"), name
        spec = read_spec(list_notebooks([name])[0])
        for key, value in MANIFESTS[name].quick.items():  # the run's non-default parameters: its preset
            assert (f"{key}=" in texts[0]) == (value != spec[key].default), (name, key)


def test_figures_name_the_runs_non_default_parameters(quick_runs):
    out, summary = quick_runs[0]
    assert MANIFESTS["05_fusion_soft"].quick == {"n_points": 11}
    svg = (out / "figures" / "fusion_soft_sweep.svg").read_text()
    footer = "synthetic data (seed 0, 1270 experiments) · 05_fusion_soft with n_points=11"
    assert f"<!-- {footer} -->" in svg  # matplotlib keeps each text as a comment in the SVG
    made = read_provenance()  # the glu that ran: its version and commit, on every figure and in the summary
    assert summary["made_by"] == made.label() and summary["provenance"] == made.as_dict()
    assert f"<!-- {made.label()} -->" in svg and made.commit is not None
    assert json.loads((out / "figures" / "rendered-with.json").read_text())["made_by"] == made.label()
    assert "data: synthetic data" not in svg  # the footer names the data once
    assert str(out) not in svg  # no machine path
    doc = json.loads((out / "results" / "fusion_soft_sweep_box.json").read_text())
    assert doc["meta"]["notebook_parameters"] == {"n_points": 11}
    plain = (out / "figures" / "glu2017_effect_prediction.svg").read_text()  # no preset: no "with"
    assert "<!-- synthetic data (seed 0, 1270 experiments) -->" in plain


@needs_browser
def test_the_site_opens_in_a_real_browser_every_page_image_and_link_working(quick_runs, tmp_path):
    """Every page of the site loads in headless Chromium without a network and without a console error; every
    internal link leads to a file (and anchor) that exists; every figure renders, and opens at its natural
    size with its caption when clicked; every table and example fits the page (a 1400 px window)."""
    out, summary = quick_runs[0]
    site = out / "site"
    packages = {
        f"api/{m}.html" for m in api_modules() if (site / "api" / f"{m}.html").is_file() and _is_package(m)
    }
    with browser(tmp_path / "profile") as driver:  # the API's modules: their links only (150 pages alike)
        seen = walk_site(driver, site, browse=lambda name: not name.startswith("api/") or name in packages)
        found = search(driver, site, "affordance")
    assert seen["problems"] == {"console": [], "links": [], "images": [], "clipped": [], "unreachable": []}
    for name in NOTEBOOKS:  # each executed notebook is a page
        assert (site / "notebooks" / f"{name}.html").is_file()
    assert "notebooks/03_bn_learning.html" in found  # the site's search, offline
    pngs = [f for f in summary["figures"] if f.endswith(".png")]
    assert seen["images"] >= 2 * len(pngs)  # each figure on its notebook's page and in the index's gallery


def _is_package(module: str) -> bool:
    import importlib

    return Path(importlib.import_module(module).__file__).name == "__init__.py"


def test_no_executed_notebook_and_no_page_of_the_site_shows_a_machine_path(quick_runs):
    out, _ = quick_runs[0]
    root = str(Path(__file__).resolve().parents[2])
    for folder in (out / "notebooks", out / "site"):
        files = [
            f for f in folder.rglob("*") if f.is_file() and f.suffix in (".ipynb", ".html", ".js", ".txt")
        ]
        assert files
        for f in files:
            text = f.read_text(encoding="utf-8", errors="replace")
            for what, needle in (
                ("project", root),
                ("home", str(Path.home())),
                ("out", str(out)),
                ("staging", ".glu-staging"),
            ):
                assert needle not in text, f"{f.relative_to(out)} shows the {what} folder"


def test_the_run_counts_the_notebooks_finished_and_the_count_only_goes_up(tmp_path):
    """[k/n] counts the notebooks finished (they finish in any order), not their place in the run order."""
    nbs = tmp_path / "nbs"
    nbs.mkdir()
    (nbs / "01_ok.py").write_text(_OK)
    (nbs / "02_ok.py").write_text(_OK)
    lines: list[str] = []
    reproduce(
        data="synthetic", jobs=2, out=tmp_path / "out", log=lines.append, notebooks_dir=nbs, site=False,
        progress=False,
    )  # fmt: skip
    counted = [line.split(" ")[0] for line in lines if line.startswith("[")]
    assert counted == ["[1/2]", "[2/2]"], lines


@pytest.mark.parametrize(
    ("block", "message"),
    [
        ("  figures: a", "figures: must be a list of names (letters, digits, _ . -), got 'a'"),
        ("  figures:\n  - ../a", "figures: must be a list of names (letters, digits, _ . -), got ['../a']"),
        ("  figures:\n  - a\n  - a", "figures: a name is listed twice"),
        ("  figure:\n  - a", "has unknown keys ['figure']; allowed: ['about', 'expected_seconds', 'figures', "
         "'models', 'quick', 'real_only', 'recordings', 'tables']"),
        ("  figures:\n  - a\n  real_only:\n  - b", "real_only: ['b'] are not among its outputs"),
        ("  quick: fast", "quick: must map parameter names to values, got 'fast'"),
        ("  about:\n  - two\n  - lines", "about: must be one line of text"),
    ],
)  # fmt: skip
def test_a_malformed_manifest_is_refused_naming_its_notebook_and_key(tmp_path, block, message):
    from glu.run.manifest import ManifestError

    path = tmp_path / "07_x.py"
    path.write_text(
        "# ---\n# jupyter:\n#   glu:\n" + "".join(f"#   {line}\n" for line in block.splitlines()) + "# ---\n"
    )
    with pytest.raises(ManifestError) as e:
        read_manifest(path)
    assert (
        str(e.value)
        == f"07_x: the glu block of its header{' ' if message.startswith('has') else ', '}{message}"
    )


def test_a_notebook_must_write_what_its_manifest_declares_for_its_data(tmp_path):
    from glu.run.manifest import Manifest, ManifestError, check_outputs

    m = Manifest("07_x", "", None, figures=("a", "b"), tables=("t",), real_only=frozenset({"b"}))
    check_outputs(m, {"figures": {"a", "b"}, "tables": {"t"}}, real=True)
    check_outputs(m, {"figures": {"a"}, "tables": {"t"}}, real=False)
    with pytest.raises(ManifestError) as e:
        check_outputs(m, {"figures": {"a", "c"}, "tables": set()}, real=True)
    assert str(e.value) == (
        "07_x (real data): figures not in its manifest: c; figures declared but not written: b; "
        "tables declared but not written: t (its manifest is the glu block of its header)"
    )
    with pytest.raises(ManifestError, match=r"^07_x \(synthetic data\): figures not in its manifest: b "):
        check_outputs(m, {"figures": {"a", "b"}, "tables": {"t"}}, real=False)


def _header(expected: float, body: str) -> str:
    return (
        _OK.replace(
            "#     about: a test notebook\n",
            f"#     about: a test notebook\n#     expected_seconds: {expected}\n",
        )
        + body
    )


@pytest.mark.slow
def test_a_failure_stops_the_notebook_running_beside_it_and_those_not_started_never_start(tmp_path):
    """-j 2: 02 (longest, first) and 01 start; 01 fails: 02 is stopped at once, and so is 03, which took
    01's place; 04, still waiting, never starts."""
    nbs = tmp_path / "nbs"
    nbs.mkdir()
    (nbs / "01_fails.py").write_text(_header(5, '\n# %%\nraise RuntimeError("deliberate failure")\n'))
    (nbs / "02_slow.py").write_text(_header(100, "\n# %%\nimport time\ntime.sleep(120)\n"))
    (nbs / "03_later.py").write_text(_header(1, ""))
    (nbs / "04_last.py").write_text(_header(0.5, ""))
    said = []
    with pytest.raises(NotebookError, match="notebook 01_fails failed in cell .* deliberate failure"):
        reproduce(
            data="synthetic", out=tmp_path / "out", jobs=2, log=said.append, notebooks_dir=nbs, site=False
        )
    finished = [line for line in said if line.startswith("[")]
    assert len(finished) == 1 and finished[0].startswith("[1/4] 01_fails: FAILED after ")
    assert not (tmp_path / "out" / "figures").exists()


@pytest.mark.slow
def test_a_notebook_that_writes_other_outputs_than_its_manifest_declares_fails(tmp_path):
    nbs = tmp_path / "nbs"
    nbs.mkdir()
    (nbs / "01_x.py").write_text(
        _OK.replace("#     about: a test notebook\n", "#     about: a test\n#     figures: [z]\n").replace(
            '"new.txt"', '"a.png"'
        )
    )
    with pytest.raises(NotebookError) as e:
        reproduce(data="synthetic", out=tmp_path / "out", log=_silent, notebooks_dir=nbs, site=False)
    assert str(e.value).startswith(
        "notebook 01_x ran, but 01_x (synthetic data): figures not in its manifest: a; figures declared but "
        "not written: z (its manifest is the glu block of its header); executed copy kept at "
    )


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"jobs": 0}, "-j 0: the number of notebooks run at once must be between 1 and 64"),
        ({"jobs": 65}, "-j 65: the number of notebooks run at once must be between 1 and 64"),
        ({"seed": -1}, "--seed -1: a seed must be between 0 and 2**32 - 1"),
        ({"seed": 2**32}, "--seed 4294967296: a seed must be between 0 and 2**32 - 1"),
        ({"notebooks_dir": "empty"}, "no notebooks found in "),
        ({"notebooks_dir": "seedless"}, "01_x: its parameters cell lacks seed"),
    ],
)
def test_reproduce_refuses_what_it_cannot_run_before_running_anything(tmp_path, kwargs, message):
    (tmp_path / "empty").mkdir()
    (tmp_path / "seedless").mkdir()
    (tmp_path / "seedless" / "01_x.py").write_text(_OK.replace("seed: int = 0  # seed\n", ""))
    if "notebooks_dir" in kwargs:
        kwargs = {"notebooks_dir": tmp_path / kwargs["notebooks_dir"]}
    with pytest.raises(NotebookError) as e:
        reproduce(
            data="synthetic",
            out=tmp_path / "out",
            log=_silent,
            **{"notebooks_dir": tmp_path / "seedless", **kwargs},
        )
    assert str(e.value).startswith(message) and not (tmp_path / "out").exists()


def test_only_a_full_real_run_with_seed_0_in_the_checkout_rewrites_the_tracked_figures(tmp_path):
    from types import SimpleNamespace

    from glu.run.reproduce import _promote_figures
    from glu.run.summary import RENDERING_RECORD

    run, tracked = tmp_path / "run", tmp_path / "tracked"
    (run / "figures").mkdir(parents=True)
    tracked.mkdir()
    for name, data in (
        ("a.png", b"new a"),
        ("b.png", b"same b"),
        ("c.svg", b"svg"),
        (RENDERING_RECORD, b"{}"),
    ):
        (run / "figures" / name).write_bytes(data)
    (tracked / "b.png").write_bytes(b"same b")
    (tracked / "a.png").write_bytes(b"old a")
    said = []

    def plan(**change):
        base = {"tracked_figures": tracked, "is_real": True, "quick": False, "seed": 0, **change}
        layout = SimpleNamespace(tracked_figures=base["tracked_figures"])
        return SimpleNamespace(
            layout=layout,
            source=SimpleNamespace(is_real=base["is_real"]),
            quick=base["quick"],
            seed=base["seed"],
        )

    for other in ({"tracked_figures": None}, {"is_real": False}, {"quick": True}, {"seed": 1}):
        _promote_figures(plan(**other), run, said.append)
    assert said == [] and (tracked / "a.png").read_bytes() == b"old a"
    _promote_figures(plan(), run, said.append)
    assert said == ["glu reproduce: 2 of the tracked figures in figures/ rewritten from the real data"]
    assert sorted(p.name for p in tracked.iterdir()) == ["a.png", "b.png", RENDERING_RECORD]
    assert (tracked / "a.png").read_bytes() == b"new a" and (tracked / RENDERING_RECORD).read_bytes() == b"{}"
