"""A browsable HTML report of a ``glu reproduce`` run: every figure, every comparison, every notebook.

:func:`write_report` writes into the layout's ``report/`` folder (by default ``build/report/``):

* ``index.html`` — the data source, the package versions, the comparisons of our numbers with the
  original models and the published values, and every figure (copied beside it into ``figures/``) with
  the notebook that drew it and the parameters it ran with;
* ``notebooks/NAME.html`` — each executed notebook rendered by nbconvert, its figures embedded
  (:func:`render_notebook_page`);
* ``api.html`` — the reference of glu's public modules, generated from their docstrings (:func:`write_api_reference`).

:func:`glu.run.reproduce.reproduce` renders each notebook's page as soon as that notebook has run, while the
others still run, and publishes the pages with the run's other outputs; the report then only copies the
figures and writes the API reference (:func:`prepare_report`) and the index (:func:`write_index`). A page
that is missing, or older than its executed notebook, is rendered there.

The pages are static files (no server, no network): open ``index.html`` in any browser. A small script
in the index marks, once the page has loaded, how many of its figures the browser rendered
(``<body data-figures-rendered="N/M">``), which the tests read back from headless Chromium.
"""

from __future__ import annotations

import html
import shutil
import threading
from collections.abc import Mapping
from functools import cache
from pathlib import Path
from typing import Any

from glu.files import atomic_write_text
from glu.paths import OutputLayout
from glu.run.outputs import parameters_text

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #ddd; }
table { border-collapse: collapse; font-size: 0.9em; } td, th { padding: 3px 10px; text-align: left; }
tr:nth-child(even) { background: #f6f6f6; } th { border-bottom: 1px solid #999; }
.grid { display: flex; flex-wrap: wrap; gap: 24px; }
figure { margin: 0; width: 560px; } figure img { width: 100%; border: 1px solid #eee; }
figcaption { font-size: 0.85em; color: #444; } code { background: #f3f3f3; padding: 0 3px; }
.ok { color: #1a7f37; } .diff { color: #b42318; }
"""

_CHECK_SCRIPT = """
window.addEventListener("load", function () {
  var imgs = document.querySelectorAll("img.figure");
  var ok = 0;
  imgs.forEach(function (im) { if (im.complete && im.naturalWidth > 0) { ok += 1; } });
  document.body.setAttribute("data-figures-rendered", ok + "/" + imgs.length);
});
"""


def _e(x: Any) -> str:
    return html.escape(str(x))


def _table(rows: list[Mapping[str, Any]], columns: list[str]) -> str:
    head = "".join(f"<th>{_e(c)}</th>" for c in columns)
    body = "".join("<tr>" + "".join(f"<td>{_e(r.get(c, ''))}</td>" for c in columns) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def notebook_page(report: Path, name: str) -> Path:
    """The page of the notebook ``name`` in the report folder ``report``: ``notebooks/NAME.html``."""
    return report / "notebooks" / f"{name}.html"


_EXPORTER_LOCK = threading.Lock()


@cache
def _html_exporter() -> Any:
    """One nbconvert exporter (lab template) for the process: building one compiles its Jinja templates
    again (the 11 pages of a run took 3.8 s with an exporter each, 3.2 s with this one)."""
    from nbconvert import HTMLExporter

    return HTMLExporter(template_name="lab")


def render_notebook_page(ipynb: Path, page: Path) -> Path:
    """Render the executed notebook ``ipynb`` to the HTML page ``page`` (nbconvert's lab template, its
    figures embedded); returns ``page``. Thread-safe: ``glu reproduce`` renders each page in the thread
    that ran its notebook, and the exporter is shared, one page at a time."""
    import nbformat

    nb = nbformat.read(ipynb, as_version=4)
    with _EXPORTER_LOCK:
        body, _ = _html_exporter().from_notebook_node(nb)
    return atomic_write_text(page, body)


API_MODULES: tuple[str, ...] = (
    "glu.schema",
    "glu.data.source",
    "glu.data.tables",
    "glu.data.trajectory_files",
    "glu.data.fetch",
    "glu.bn.model",
    "glu.bn.learning",
    "glu.bn.inference",
    "glu.bn.exchange",
    "glu.fusion",
    "glu.gestures.features",
    "glu.gestures.recognizer",
    "glu.gestures.typicality",
    "glu.hmm.training",
    "glu.language.grammar",
    "glu.language.descriptions",
    "glu.experiments.fusion",
    "glu.paths",
)
"""The modules of the API reference, in reading order."""


def write_api_reference(path: Path, modules: tuple[str, ...] = API_MODULES) -> Path:
    """Write the API reference of ``modules`` as one HTML page, from their docstrings (the standard
    library's :mod:`pydoc`); file links are shown relative to the package, never as machine paths."""
    import importlib
    import pydoc
    import re

    from glu.paths import PACKAGE_DIR

    doc = pydoc.HTMLDoc()
    sections, toc = [], []
    for name in modules:
        mod = importlib.import_module(name)
        body = doc.docmodule(mod)
        body = re.sub(r'<a href="file:[^"]*">([^<]*)</a>', lambda m: _e(Path(m.group(1)).name), body)
        body = body.replace(str(PACKAGE_DIR.parent), "").replace(str(PACKAGE_DIR), "glu")
        sections.append(f'<section id="{_e(name)}">{body}</section>')
        summary = (mod.__doc__ or "").strip().splitlines()[0] if mod.__doc__ else ""
        toc.append(f'<li><a href="#{_e(name)}"><code>{_e(name)}</code></a> — {_e(summary)}</li>')
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>glu — API reference</title>
<style>{_STYLE} section {{ margin-top: 3em; }}</style></head>
<body><h1>glu — API reference</h1>
<p>Generated from the docstrings of the installed package. <a href="index.html">Back to the report</a>.</p>
<ul>{"".join(toc)}</ul>
{"".join(sections)}
</body></html>
"""
    atomic_write_text(path, page)
    return path


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink()


def write_report(layout: OutputLayout, summary: Mapping[str, Any]) -> Path:
    """Write the report of a run whose outputs are in ``layout``; returns ``index.html``.

    ``summary`` is the run's summary (:func:`glu.run.summary.write_summary`): its figures, notebooks,
    comparisons, data source and versions. :func:`prepare_report`, then :func:`write_index`.
    """
    return write_index(layout, summary, prepare_report(layout, summary))


def prepare_report(layout: OutputLayout, summary: Mapping[str, Any]) -> dict[str, str]:
    """Everything of the report but its index: the folder cleared of all but the pages of the summary's
    notebooks, the figures copied, a page rendered for each notebook whose page is missing or older than
    its executed notebook, the API reference written. Returns notebook → its page (relative to the report).
    """
    root = layout.report
    names = [nb["name"] for nb in summary.get("notebooks", [])]
    keep = {notebook_page(root, name) for name in names}
    (root / "notebooks").mkdir(parents=True, exist_ok=True)
    for item in [*root.iterdir(), *(root / "notebooks").iterdir()]:  # a fresh report, but for the pages
        if item != root / "notebooks" and item not in keep:  # of its notebooks (rendered as each ran)
            _remove(item)
    (root / "figures").mkdir()
    pages = {}
    for name in names:
        page, ipynb = notebook_page(root, name), layout.notebooks / f"{name}.ipynb"
        if ipynb.is_file() and (not page.is_file() or page.stat().st_mtime_ns < ipynb.stat().st_mtime_ns):
            render_notebook_page(ipynb, page)
        if page.is_file():
            pages[name] = page.relative_to(root).as_posix()
    for fname in summary.get("figures_by_notebook", {}):
        src = layout.figures / fname
        if fname.endswith(".png") and src.is_file():
            shutil.copyfile(src, root / "figures" / fname)
    write_api_reference(root / "api.html")
    return pages


def write_index(layout: OutputLayout, summary: Mapping[str, Any], pages: Mapping[str, str]) -> Path:
    """Write the report's ``index.html`` (after :func:`prepare_report`, which gives ``pages``); returns it."""
    root = layout.report
    notebooks = {nb["name"]: nb for nb in summary.get("notebooks", [])}
    figures = []
    by_notebook = summary.get("figures_by_notebook", {})
    for fname, nb in sorted(by_notebook.items(), key=lambda item: (item[1], item[0])):
        if not fname.endswith(".png") or not (root / "figures" / fname).is_file():
            continue
        params = notebooks.get(nb, {}).get("parameters") or {}
        label = parameters_text(params) or "default parameters"
        link = f'<a href="{_e(pages[nb])}">{_e(nb)}</a>' if nb in pages else _e(nb)
        figures.append(
            f'<figure><img class="figure" src="figures/{_e(fname)}" alt="{_e(fname)}">'
            f"<figcaption><code>{_e(fname[:-4])}</code> — {link} — {_e(label)}</figcaption></figure>"
        )

    comparisons = [
        {**c, "max |ours − reference|": f"{c['max_abs_difference']:.3g}"}
        for c in summary.get("comparison_with_reference", [])
    ]
    nb_rows = [
        {
            "notebook": n["name"],
            "status": n["status"],
            "seconds": n.get("seconds", ""),
            "parameters": parameters_text(n.get("parameters") or {}) or "defaults",
        }
        for n in notebooks.values()
    ]
    versions = [{"package": k, "version": v} for k, v in summary.get("versions", {}).items()]
    recordings = "".join(f"<li><code>recordings/{_e(r)}</code></li>" for r in summary.get("recordings", []))
    nb_links = "".join(f'<li><a href="{_e(p)}">{_e(n)}</a></li>' for n, p in sorted(pages.items()))
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>glu — reproduced figures</title>
<style>{_STYLE}</style><script>{_CHECK_SCRIPT}</script></head>
<body>
<h1>glu — gestures, language and affordances, reproduced</h1>
<p><b>Data:</b> {_e(summary.get("data_source", "unknown"))} · <b>mode:</b> {"quick" if summary.get("quick") else "full"}
· <b>wall time:</b> {_e(summary.get("wall_time_s", ""))} s · {len(figures)} figures</p>
<h2>Ours against the originals</h2>
{_table(comparisons, ["table", "reference", "rows", "max |ours − reference|"]) if comparisons else "<p>No reference to compare with in this data.</p>"}
<h2>Figures</h2>
<div class="grid">{"".join(figures)}</div>
<h2>Notebooks</h2>
<ul>{nb_links}</ul>
{_table(nb_rows, ["notebook", "status", "seconds", "parameters"])}
<h2>Recordings</h2>
<p>Open with <code>rerun FILE</code> (the Rerun viewer).</p><ul>{recordings}</ul>
<h2>Python API</h2>
<p>The reference of glu's public modules, from their docstrings: <a href="api.html">api.html</a>.</p>
<h2>Package versions</h2>
{_table(versions, ["package", "version"])}
</body></html>
"""
    index = root / "index.html"
    atomic_write_text(index, page)
    return index
