"""`glu reproduce` renders each notebook's report page as soon as that notebook has run (in its worker, into
the staging folder), publishes the pages with the run's other outputs only when every notebook succeeded,
and records a wall time that covers the report; the report at the end reuses the pages."""

from __future__ import annotations

import json
import os
import threading
import time

import pytest

from glu.paths import STAGING, OutputLayout
from glu.run import report as report_module
from glu.run import reproduce as reproduce_module
from glu.run.reproduce import NotebookError, reproduce

_NB = """# ---
# jupyter:
#   glu:
#     about: a test notebook
# ---

# %% tags=["parameters"]
data: str = None  # data folder
seed: int = 0  # seed
out_dir: str = None  # outputs

# %%
import time
from pathlib import Path
wait_for = WAIT  # a file that appears when another notebook's page has been rendered
deadline = time.monotonic() + 30
while wait_for and not Path(wait_for).exists() and time.monotonic() < deadline:
    time.sleep(0.05)
Path(out_dir, "figures").mkdir(parents=True, exist_ok=True)
saw = bool(wait_for) and Path(wait_for).exists()
Path(out_dir, "figures", NAME + ".txt").write_text(f"seed {seed}, saw the page: {saw}")
"""

_FAILS = """# ---
# jupyter:
#   glu:
#     about: a test notebook
# ---

# %% tags=["parameters"]
data: str = None  # data folder
seed: int = 0  # seed
out_dir: str = None  # outputs

# %%
raise RuntimeError("deliberate failure")
"""


def _snapshot(folder):
    return sorted(
        (str(p.relative_to(folder)), p.read_bytes(), p.stat().st_mtime_ns)
        for p in folder.rglob("*")
        if p.is_file()
    )


@pytest.fixture
def renders(monkeypatch, tmp_path):
    """Every page rendered (target, thread), by reproduce's workers or by the report at the end; a marker
    file ``rendered-NAME`` appears beside ``tmp_path`` once a page is written."""
    calls: list[tuple[str, str, bool]] = []
    real = report_module.render_notebook_page
    fail = set()

    def render(ipynb, page):
        if page.stem in fail:
            raise ValueError("no template")
        out = real(ipynb, page)
        calls.append((page.stem, str(page), threading.current_thread() is threading.main_thread()))
        (tmp_path / f"rendered-{page.stem}").write_text("")
        return out

    monkeypatch.setattr(reproduce_module, "render_notebook_page", render)
    monkeypatch.setattr(report_module, "render_notebook_page", render)
    render.calls, render.fail = calls, fail
    return render


def test_each_page_is_rendered_as_its_notebook_finishes_and_published_only_with_the_run(
    tmp_path, monkeypatch, renders
):
    nbs, out = tmp_path / "nbs", tmp_path / "out"
    nbs.mkdir()
    (nbs / "01_a.py").write_text(_NB.replace("NAME", repr("01_a")).replace("WAIT", "None"))
    marker = repr(str(tmp_path / "rendered-01_a"))  # 02_b finishes only once 01_a's page exists
    (nbs / "02_b.py").write_text(_NB.replace("NAME", repr("02_b")).replace("WAIT", marker))
    lines: list[tuple[float, str]] = []
    timed: dict[str, float] = {}
    real_prepare = reproduce_module.prepare_report

    def prepare(layout, summary):
        pages = real_prepare(layout, summary)
        timed["prepared"] = time.perf_counter()
        return pages

    monkeypatch.setattr(reproduce_module, "prepare_report", prepare)
    t_call = time.perf_counter()
    summary = reproduce(
        data="synthetic",
        out=out,
        jobs=2,
        notebooks_dir=nbs,
        log=lambda s: lines.append((time.perf_counter(), s)),
    )
    t_return = time.perf_counter()

    # rendered in the workers, into the staging folder, while the other notebook still ran
    assert sorted(name for name, _, _ in renders.calls) == ["01_a", "02_b"]
    assert all(STAGING in target and not in_main for _, target, in_main in renders.calls), renders.calls
    assert (out / "figures" / "02_b.txt").read_text().endswith("saw the page: True")
    # published beside the run's other outputs; the report links them and did not render them again
    layout = OutputLayout.at(out)
    index = (layout.report / "index.html").read_text()
    for name in ("01_a", "02_b"):
        page = layout.report / "notebooks" / f"{name}.html"
        assert page.is_file() and f'href="notebooks/{name}.html"' in index
        assert "saw the page" in page.read_text()  # the executed notebook, its source shown
    assert (layout.report / "api.html").is_file()
    assert not (out / STAGING).exists() or not any((out / STAGING).iterdir())

    # the wall time covers the report, and the log, the summary file and the index state that same figure
    wall = summary["wall_time_s"]
    assert wall >= timed["prepared"] - lines[0][0] - 0.001  # the first line is logged after the clock starts
    assert wall <= t_return - t_call
    assert json.loads((layout.results / "summary.json").read_text())["wall_time_s"] == wall
    assert lines[-1][1].startswith(f"glu reproduce: done in {wall:.1f} s")
    assert f"<b>wall time:</b> {wall} s" in index

    # a partial run replaces its notebook's page and keeps the other's as it was
    kept = (layout.report / "notebooks" / "01_a.html").stat().st_mtime_ns
    before = (layout.report / "notebooks" / "02_b.html").read_text()
    renders.calls.clear()
    part = reproduce(
        data="synthetic", out=out, jobs=2, notebooks_dir=nbs, only=["02"], seed=7, log=lambda _: None
    )
    assert [n["name"] for n in part["notebooks"]] == ["01_a", "02_b"]
    assert [name for name, _, _ in renders.calls] == ["02_b"]
    assert (layout.report / "notebooks" / "01_a.html").stat().st_mtime_ns == kept
    assert (layout.report / "notebooks" / "02_b.html").read_text() != before  # seed 7 now
    assert 'href="notebooks/01_a.html"' in (layout.report / "index.html").read_text()

    # a failed run publishes no page, though the notebook that succeeded had its page rendered
    (nbs / "03_fails.py").write_text(_FAILS)
    published = _snapshot(layout.report)
    renders.calls.clear()
    with pytest.raises(NotebookError, match="03_fails failed in cell"):
        reproduce(data="synthetic", out=out, jobs=1, notebooks_dir=nbs, only=["01", "03"], log=lambda _: None)
    assert [name for name, _, _ in renders.calls] == ["01_a"]
    assert _snapshot(layout.report) == published

    # a page that cannot be rendered fails the run like a failing cell: nothing published
    renders.fail.add("01_a")
    with pytest.raises(NotebookError, match="01_a ran, but its report page could not be rendered"):
        reproduce(data="synthetic", out=out, jobs=1, notebooks_dir=nbs, only=["01"], log=lambda _: None)
    assert _snapshot(layout.report) == published
    assert (layout.notebooks / "01_a.failed.ipynb").is_file()

    # without the report, no page is rendered and the report is left as it was
    renders.fail.clear()
    renders.calls.clear()
    reproduce(
        data="synthetic", out=out, jobs=1, notebooks_dir=nbs, only=["01"], report=False, log=lambda _: None
    )
    assert renders.calls == [] and _snapshot(layout.report) == published


def test_the_report_renders_only_the_pages_that_are_missing_or_older_than_their_notebook(tmp_path, renders):
    import nbformat

    layout = OutputLayout.under(tmp_path / "out")
    for name in ("a", "b", "c"):
        nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell(f"notebook {name} speaks")])
        layout.notebooks.mkdir(parents=True, exist_ok=True)
        nbformat.write(nb, layout.notebooks / f"{name}.ipynb")
    pages = layout.report / "notebooks"
    pages.mkdir(parents=True)
    (pages / "a.html").write_text("<p>rendered by its run</p>")  # newer than its notebook: kept
    (pages / "b.html").write_text("<p>an earlier run</p>")  # older than its notebook: rendered again
    old = (layout.notebooks / "b.ipynb").stat().st_mtime_ns - 10**9
    os.utime(pages / "b.html", ns=(old, old))
    (pages / "gone.html").write_text("a notebook no longer in the summary")
    (layout.report / "leftover.txt").write_text("from an older report")
    summary = {
        "notebooks": [{"name": n, "status": "ok", "seconds": 1.0} for n in ("a", "b", "c")],
        "wall_time_s": 2.5,
    }
    index = report_module.write_report(layout, summary)
    assert (pages / "a.html").read_text() == "<p>rendered by its run</p>"
    assert "notebook b speaks" in (pages / "b.html").read_text()
    assert "notebook c speaks" in (pages / "c.html").read_text()  # missing: rendered
    assert sorted(name for name, _, _ in renders.calls) == ["b", "c"]
    assert sorted(p.name for p in layout.report.iterdir()) == [
        "api.html",
        "figures",
        "index.html",
        "notebooks",
    ]
    assert sorted(p.name for p in pages.iterdir()) == ["a.html", "b.html", "c.html"]
    assert all(f'href="notebooks/{n}.html"' in index.read_text() for n in "abc")
