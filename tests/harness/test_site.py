"""The documentation site (glu.run.site): captions from the notebooks' prose, executed notebooks without
machine paths, and a small run on a data folder on disk whose site shows none of this machine's paths."""

from __future__ import annotations

import json
import re
from pathlib import Path

import nbformat
import pytest

from glu import paths
from glu.paths import RUNS, OutputLayout
from glu.run import site as site_module
from glu.run.captions import caption_figures, figure_captions
from glu.run.execution import present_executed, shown_path
from glu.run.publish import republish
from glu.run.reproduce import reproduce
from glu.run.site import SiteError, build_site
from glu.run.site_api import api_modules


def _figure_cell(name: str) -> nbformat.NotebookNode:
    cell = nbformat.v4.new_code_cell("out.figure(fig, 'x')")
    cell.outputs = [
        nbformat.v4.new_output(
            "display_data", data={"image/png": "iVBORw0KGgo="}, metadata={"glu": {"figure": f"{name}.png"}}
        )
    ]
    return cell


def test_a_figures_caption_is_its_sections_title_and_the_sentence_that_interprets_it():
    md, code = nbformat.v4.new_markdown_cell, nbformat.v4.new_code_cell
    nb = nbformat.v4.new_notebook(
        cells=[
            md("# 07 · The figures\n\nThe notebook's introduction."),
            _figure_cell("a"),  # followed by its interpretation
            md("The sphere rolls away,\nthe box stays.\n\nA second paragraph."),
            md(
                "## Fig. 5 · Word changes\nHow the words change with the tap."
            ),  # heading and text, no blank line
            _figure_cell("b"),  # followed by a new section: the text under its own heading
            code("x = 1"),
            md("## Another section:\n\n### Its part"),
            _figure_cell("c"),  # a heading without text, nothing after: the title alone
        ]
    )
    assert figure_captions(nb) == {
        1: ("The figures", "The sphere rolls away, the box stays."),
        4: ("Fig. 5 · Word changes", "How the words change with the tap."),
        7: ("Its part", ""),
    }
    captions = caption_figures(nb)
    assert captions == {
        "a.png": "**The figures.** The sphere rolls away, the box stays.",
        "b.png": "**Fig. 5 · Word changes.** How the words change with the tap.",
        "c.png": "**Its part.**",
    }
    assert nb.cells[4].outputs[0].metadata["glu"] == {
        "figure": "b.png",
        "title": "Fig. 5 · Word changes",
        "text": "How the words change with the tap.",
    }


def test_a_folder_is_shown_relative_to_the_project_or_by_its_name_only(tmp_path):
    root = tmp_path / "project"
    assert shown_path(root / "data" / "real", root) == "data/real"
    assert shown_path(root, root) == "."
    assert shown_path(tmp_path / "elsewhere" / "data", root) == "…/data"


def test_the_executed_notebook_names_the_published_folders_not_the_staging_one(tmp_path):
    nb = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_code_cell("data = None  # data folder\nout_dir = None  # outputs"),
            nbformat.v4.new_code_cell(
                f'# Parameters\nseed = 0\ndata = "{tmp_path}/data"\nout_dir = '
                f'"{tmp_path}/{RUNS}/abc/01/out"\n',
                metadata={"tags": ["injected-parameters"]},
            ),
        ]
    )
    nb.metadata["papermill"] = {
        "parameters": {"seed": 0, "data": f"{tmp_path}/data", "out_dir": f"{tmp_path}/{RUNS}/abc/01/out"},
        "input_path": {"cells": "the whole notebook"},
        "output_path": f"{tmp_path}/{RUNS}/abc/01/01.ipynb",
    }
    ipynb = tmp_path / "01.ipynb"
    nbformat.write(nb, ipynb)
    present_executed(
        ipynb,
        {"data": ("…/data", "real data: origin@1234"), "out_dir": (".", "published there")},
        "notebooks/01.py",
        "build/notebooks/01.ipynb",
    )
    text = ipynb.read_text()
    assert str(tmp_path) not in text and RUNS not in text
    done = nbformat.read(ipynb, as_version=4)
    assert done.cells[1].source.split("\n") == [
        "# Parameters",
        "seed = 0",
        'data = "…/data"  # real data: origin@1234',
        'out_dir = "."  # published there',
        "",
    ]
    assert done.cells[0].source == nb.cells[0].source  # the notebook's own parameters cell is as it was
    assert done.metadata.papermill.parameters == {"seed": 0, "data": "…/data", "out_dir": "."}
    assert done.metadata.papermill.input_path == "notebooks/01.py"
    assert done.metadata.papermill.output_path == "build/notebooks/01.ipynb"


SOME_MODULES = ("glu", "glu.bn", "glu.bn.model", "glu.hmm", "glu.hmm.model", "glu.run", "glu.run.manifest")
"""The API reference of the small site: a few packages and modules (the complete one is the quick run's,
tests/harness/test_notebooks.py)."""


@pytest.fixture(scope="module")
def site_run(tmp_path_factory, synthetic_folder):
    """A quick run of two notebooks on a data folder on disk (not the project's), with its site."""
    out = tmp_path_factory.mktemp("site-run") / "out"
    summary = reproduce(
        data=synthetic_folder, quick=True, out=out, jobs=2, only=["01", "08"], log=lambda _: None, site=False
    )
    layout = OutputLayout.under(out)  # the site of the published run, with the small API reference
    republish(
        layout,
        "site",
        lambda staged, work: build_site(staged, modules=SOME_MODULES, work=work, published=layout),
    )
    return out, summary


def _machine_paths(folder: Path, data: Path, out: Path) -> dict[str, list[str]]:
    """Which of this machine's paths each text file under ``folder`` shows."""
    needles = {
        "the project root": str(paths.PROJECT_ROOT),
        "the data folder": str(data),
        "the home folder": str(Path.home()),
        "the output folder": str(out),
    }
    # a run's own folder in the store (the docs may name the store and its current and failed places)
    staging = re.compile(re.escape(RUNS) + r"/(?!current\b|failed\b)[\w.-]+")
    found: dict[str, list[str]] = {}
    for f in sorted(folder.rglob("*")):
        if not f.is_file() or f.suffix in (".png", ".svg", ".woff", ".woff2", ".ttf", ".ico", ".gif", ".jpg"):
            continue
        text = f.read_text(encoding="utf-8", errors="replace")
        hits = [what for what, needle in needles.items() if needle in text]
        hits += ["the staging folder"] if staging.search(text) else []
        if hits:
            found[f.relative_to(folder).as_posix()] = hits
    return found


def test_no_notebook_and_no_page_of_the_site_shows_a_path_of_this_machine(site_run, synthetic_folder):
    out, _ = site_run
    layout = OutputLayout.under(out)
    assert sorted(p.name for p in layout.notebooks.glob("*.ipynb")) == [
        "01_gesture_features.ipynb",
        "08_tcds_figures.ipynb",
    ]
    assert (layout.site / "index.html").is_file()
    for folder in (layout.notebooks, layout.site):
        assert _machine_paths(folder, synthetic_folder, out) == {}, folder.name
    injected = [
        c
        for c in json.loads((layout.notebooks / "08_tcds_figures.ipynb").read_text())["cells"]
        if "injected-parameters" in c["metadata"].get("tags", [])
    ]
    source = "".join(injected[0]["source"])
    from glu.data import resolve_data

    described = resolve_data(synthetic_folder).describe()  # named by what it is, never by its path
    assert f'data = "…/{synthetic_folder.name}"  # {described}' in source
    assert f'out_dir = "…/{out.name}"' in source


def test_the_site_has_the_notebooks_the_docs_the_api_and_the_recordings(site_run):
    out, summary = site_run
    site = OutputLayout.under(out).site
    for name in ("01_gesture_features", "08_tcds_figures"):
        page = (site / "notebooks" / f"{name}.html").read_text()
        assert 'class="glu-figure' in page and "glu-interpretation" in page
    index = (site / "index.html").read_text()
    for rec in summary["recordings"]:
        assert f"<code>rerun recordings/{rec}</code>" in index and f'href="../recordings/{rec}"' in index
    assert summary["recordings"] and summary["versions"]["numpy"] in index
    assert summary["data_source"] in index  # the data source, named without its path
    assert index.count("<figure") >= len([f for f in summary["figures"] if f.endswith(".png")])
    for module in SOME_MODULES:
        page = (site / "api" / f"{module}.html").read_text()
        assert "__dataclass_fields__" not in page and "__delattr__" not in page and "__init__" not in page
    manifest = (site / "api" / "glu.run.manifest.html").read_text()
    assert "expected_seconds" in manifest and "Manifest" in manifest  # a dataclass, its fields listed
    docs = sorted(p.stem for p in (paths.PROJECT_ROOT / "docs").glob("*.md"))
    assert docs and all((site / "docs" / f"{d}.html").is_file() for d in docs)
    assert (site / "search.html").is_file() and (site / "searchindex.js").is_file()


def test_a_package_page_links_the_names_it_gathers_to_where_they_are_documented(site_run):
    out, _ = site_run
    api = OutputLayout.under(out).site / "api"
    bn = (api / "glu.bn.html").read_text()
    assert 'href="glu.bn.model.html#glu.bn.model.BayesNet"' in bn  # glu.bn.BayesNet, defined in glu.bn.model
    assert 'href="glu.bn.model.html"' in bn  # its modules
    hmm = (api / "glu.hmm.html").read_text()
    assert 'href="glu.hmm.model.html#glu.hmm.model.GestureHMM"' in hmm
    assert 'id="glu.hmm.model.GestureHMM"' in (api / "glu.hmm.model.html").read_text()
    index = (OutputLayout.under(out).site / "api.html").read_text()
    order = [index.index(f'href="api/{m}.html#module-{m}"') for m in ("glu", "glu.hmm", "glu.bn", "glu.run")]
    assert order == sorted(order)  # layer by layer, bottom first


def test_the_api_reference_has_every_public_module_in_the_order_of_the_layers():
    from test_layout import LAYER, component, modules

    shipped = ("glu.resources.", "glu.notebooks.")  # the site's configuration, the notebooks: not API
    public = {
        m for m in modules() if not any(p.startswith("_") for p in m.split(".")) and not m.startswith(shipped)
    }
    assert set(api_modules()) == public  # every public module, found by walking the package
    assert {"glu", "glu.bn", "glu.hmm", "glu.bn.soft", "glu.gestures.invariants", "glu.plots"} <= public
    layers = [LAYER[component(m)] for m in api_modules()]
    assert layers == sorted(layers)


def test_make_docs_builds_the_site_again_from_the_last_run_and_a_warning_fails_it(
    site_run, monkeypatch, tmp_path, capsys
):
    out, _ = site_run
    layout = OutputLayout.under(out)
    pages = sorted(p.relative_to(layout.site) for p in layout.site.rglob("*.html"))
    monkeypatch.setattr(site_module, "api_modules", lambda: SOME_MODULES)  # the small reference again
    results = (layout.results / "summary.json").read_bytes()
    assert site_module.main(["--out", str(out)]) == 0  # `make docs`, from results/summary.json
    assert sorted(p.relative_to(layout.site) for p in layout.site.rglob("*.html")) == pages
    assert (layout.results / "summary.json").read_bytes() == results  # the same run, published again
    before = (layout.site / "index.html").read_bytes()
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "broken.md").write_text(
        "# Broken\n\nSee {ref}`no-such-label` and {py:func}`glu.bn.model.no_such_function`.\n"
    )
    monkeypatch.setattr(site_module, "DOCS_DIR", docs)
    runs = sorted((layout.store).iterdir())
    capsys.readouterr()
    assert site_module.main(["--out", str(out)]) == 2  # `make docs` fails, and publishes nothing
    err = capsys.readouterr().err
    assert re.search(r"(?s)2 Sphinx warning.*no-such-label", err), err
    assert "the reference to glu.bn.model.no_such_function leads to no page" in err
    assert str(out) not in err and str(paths.PROJECT_ROOT) not in err
    assert sorted((layout.store).iterdir()) == runs  # no staging left behind
    assert (layout.site / "index.html").read_bytes() == before  # the published site is as it was
    assert not (layout.site / "docs" / "broken.html").exists()


def test_the_site_needs_a_run(tmp_path):
    with pytest.raises(SiteError, match="run `glu reproduce` first"):
        build_site(OutputLayout.under(tmp_path), log=lambda _: None)


def _build(src: Path, out: Path, warnings=None) -> None:
    """Sphinx on the project ``src`` into ``out/html``, its registrations undone afterwards (as glu's own
    build does: a later build in this process must not find them)."""
    from sphinx.application import Sphinx
    from sphinx.util.docutils import docutils_namespace, patch_docutils

    with patch_docutils(src), docutils_namespace():
        Sphinx(src, src, out / "html", out / "doctrees", "html", status=None, warning=warnings).build()


@pytest.mark.slow
def test_formulas_are_mathml_a_numbered_one_with_its_number_an_unreadable_one_a_warning(tmp_path):
    """glu.run.site_math alone in a one-page Sphinx project: x^2 as MathML, the number of a labelled
    formula beside it, and a formula latex2mathml cannot read shown as its LaTeX, with a warning."""
    import io

    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text('extensions = ["glu.run.site_math"]\nhtml_math_renderer = "mathml"\n')
    (src / "index.rst").write_text(
        "Page\n====\n\nInline :math:`x^2` and :math:`\\frac{`.\n\n"
        ".. math:: y^2\n   :label: square\n\n.. math:: z^\n"
    )
    warnings = io.StringIO()
    _build(src, tmp_path, warnings)
    page = (tmp_path / "html" / "index.html").read_text()
    mathml = '<math xmlns="http://www.w3.org/1998/Math/MathML" display='
    assert f'<span class="math notranslate">{mathml}"inline"><mrow><msup><mi>x</mi><mn>2</mn></msup>' in page
    assert f'<span class="eqno">(1)</span>{mathml}"block"><mrow><msup><mi>y</mi><mn>2</mn></msup>' in page
    assert page.count('class="eqno"') == 1
    assert "<code>\\frac{</code>" in page and "<pre>z^" in page
    said = warnings.getvalue()
    assert "a formula could not be read (NoAvailableTokensError): \\frac{" in said
    assert "a formula could not be read (MissingSuperScriptOrSubscriptError): z^" in said


@pytest.mark.slow
def test_only_a_figure_with_a_caption_becomes_a_captioned_figure(tmp_path):
    """glu's MyST-NB renderer alone in a one-notebook Sphinx project: an image whose output metadata has
    a title is a captioned figure; one with only its file name, or no glu metadata, stays a plain image."""
    png = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNkYPhfDwAChwGA60e6kgAAAABJRU5ErkJggg=="
    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        'extensions = ["myst_nb"]\nnb_render_plugin = "glu"\nnb_execution_mode = "off"\n'
    )
    cell = nbformat.v4.new_code_cell("x")
    cell.outputs = [
        nbformat.v4.new_output("display_data", data={"image/png": png}, metadata=meta)
        for meta in ({"glu": {"figure": "a.png", "title": "Section A"}}, {"glu": {"figure": "b.png"}}, {})
    ]
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell("# Title"), cell])
    nbformat.write(nb, src / "index.ipynb")
    _build(src, tmp_path)
    page = (tmp_path / "html" / "index.html").read_text()
    assert page.count("<img ") == 3 and page.count("<figure") == 1
    figure = page[page.index("<figure") : page.index("</figure>")]
    assert '<img alt="a.png"' in figure and "Section A" in figure and "<code" in figure
    assert 'alt="b.png"' not in page


def test_a_package_page_documents_the_names_it_takes_from_a_private_module_itself(tmp_path, monkeypatch):
    from glu.run.site_api import module_page

    pkg = tmp_path / "glu_demo"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        '"""A package."""\nfrom glu_demo._impl import Hidden, helper\nfrom glu_demo.shown import visible\n'
    )
    (pkg / "_impl.py").write_text("class Hidden:\n    pass\n\n\ndef helper():\n    pass\n")
    (pkg / "shown.py").write_text("def visible():\n    pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    page = module_page("glu_demo", ("glu_demo", "glu_demo.shown"))
    assert page.endswith("\n.. autoclass:: glu_demo.Hidden\n\n.. autofunction:: glu_demo.helper\n")
    assert "   visible\n   Hidden\n   helper\n" in page and "glu_demo.visible" not in page  # on its own page


def test_the_index_of_a_run_without_figures_recordings_or_notebook_sources(tmp_path):
    """A summary whose notebooks have no readable source here (gone, or a malformed header) and whose
    figure files are missing: the rows without what they show, the gallery and recordings say so."""
    from glu.run.site_pages import index_page

    nbs = tmp_path / "nbs"
    nbs.mkdir()
    (nbs / "08_bad.py").write_text("---\njupyter:\n  glu: 3\n---\n")
    summary = {
        "notebooks": [
            {"name": "07_gone", "status": "ok", "seconds": 1.5},
            {"name": "08_bad", "status": "ok"},
        ],
        "figures_by_notebook": {"x.png": "07_gone"},
    }
    page = index_page(OutputLayout.under(tmp_path / "out"), summary, {}, nbs, has_docs=False)
    assert "| [07_gone](notebooks/07_gone.ipynb) |  | ok | 1.5 | defaults |" in page
    assert "| [08_bad](notebooks/08_bad.ipynb) |  | ok |  | defaults |" in page
    assert (
        "\nThis run drew no figures.\n" in page and "## Recordings\n\nThis run wrote no recordings.\n" in page
    )


def test_the_site_refuses_unreadable_parts_and_gives_a_notebook_without_one_a_title(tmp_path, monkeypatch):
    from glu.run.site import assemble

    layout = OutputLayout.under(tmp_path / "out")
    layout.results.mkdir(parents=True)
    (layout.results / "summary.json").write_text("{not json")
    with pytest.raises(
        SiteError, match=r"summary.json in results/ is not JSON \(.+\); run `glu reproduce` again"
    ):
        build_site(layout, log=lambda _: None)
    summary = {"notebooks": [{"name": "01_x", "status": "ok"}]}
    source = tmp_path / "src"
    with pytest.raises(SiteError, match=r"^the executed notebook 01_x.ipynb is missing from notebooks/$"):
        assemble(layout, summary, source, notebooks_dir=tmp_path, modules=())
    layout.notebooks.mkdir(parents=True)
    untitled = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("x = 1")])
    nbformat.write(untitled, layout.notebooks / "01_x.ipynb")
    monkeypatch.setattr(site_module, "DOCS_DIR", None)  # glu installed: no docs pages
    assemble(layout, summary, source, notebooks_dir=tmp_path, modules=())
    page = nbformat.read(source / "notebooks" / "01_x.ipynb", as_version=4)
    assert [(c.cell_type, c.source) for c in page.cells] == [("markdown", "# 01_x"), ("code", "x = 1")]
    assert not (source / "docs.md").exists() and "docs\n" not in (source / "index.md").read_text()
    layout.site.mkdir()
    with pytest.raises(SiteError, match="exists; the site is built into a run being staged"):
        build_site(layout, summary=summary, log=lambda _: None)


@pytest.mark.slow
def test_make_docs_is_python_m_glu_run_site_and_needs_a_run(tmp_path):
    import subprocess
    import sys

    r = subprocess.run(
        [sys.executable, "-m", "glu.run.site", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.startswith("glu site: error: no run is published in ") and r.stderr.count("\n") == 1
