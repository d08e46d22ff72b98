"""The documentation site of a run: the executed notebooks, the docs pages and the API reference, with Sphinx.

``glu reproduce`` ends with :func:`build_site`, which writes the layout's ``site/`` folder (``build/site/`` in
a checkout, ``OUT/site/`` with ``--out``); ``make docs`` (``python -m glu.run.site``) builds it again from the
last run. The site is made with the tools of the scientific Python ecosystem's notebook collections: Sphinx,
MyST-NB (the stack of Jupyter Book 1) and the PyData theme. It holds

* the **index**: the data source, the comparison of our numbers with the originals', every figure with its
  caption and its notebook, the notebooks with their times and parameters, the Rerun recordings with the
  command that opens them, and the package versions;
* each **executed notebook** as a page, its outputs as ``glu reproduce`` executed them (MyST-NB's
  ``nb_execution_mode = "off"``: nothing runs again), each figure with its caption
  (:func:`glu.run.captions.caption_figures`);
* the **docs pages** of the checkout (``docs/*.md``);
* the **API reference**, generated from the numpydoc docstrings of :data:`API_MODULES` (autodoc, autosummary,
  napoleon);
* search (Sphinx's own, offline). A click on any figure opens it at its natural size with its caption.

The sources are assembled in the store's ``site-source/`` folder (kept, with Sphinx's doctrees, so that the
next build only reads again what changed); the HTML is written there afresh and then copied into the run
being staged, which :mod:`glu.run.publish` publishes whole, so a failed build publishes nothing. Any Sphinx
warning fails the build (:class:`SiteError`). What the site reads of a run is checked first: a malformed
``summary.json``, a name in it that is not a plain file name, or an executed notebook that is truncated or
empty is refused in one line (:func:`read_summary`, :func:`assemble`). Nothing is fetched from the web: the
theme's files are installed with it.
"""

from __future__ import annotations

import io
import json
import os
import re
import shutil
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from glu import paths
from glu.errors import GluError
from glu.paths import OutputLayout
from glu.run.captions import caption_figures
from glu.run.manifest import ManifestError, read_manifest
from glu.run.outputs import parameters_text
from glu.run.summary import SummaryError, check_summary

CONF_DIR: Path = paths.RESOURCES_DIR / "site"
"""Sphinx's configuration, static files and templates of the site (shipped with the package)."""

DOCS_DIR: Path | None = paths.PROJECT_ROOT / "docs" if paths.PROJECT_ROOT is not None else None
"""The checkout's docs pages (``docs/*.md``), or None for an installed package."""

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
    "glu.evidence",
    "glu.fusion",
    "glu.gestures.features",
    "glu.gestures.recognizer",
    "glu.gestures.typicality",
    "glu.hmm.config",
    "glu.hmm.training",
    "glu.language.grammar",
    "glu.language.descriptions",
    "glu.studies.replication.fusion",
    "glu.recording",
    "glu.run.manifest",
    "glu.paths",
)
"""The modules of the API reference, in reading order."""


class SiteError(GluError):
    """The documentation site could not be built (a Sphinx warning or error, or no executed notebooks)."""


# ------------------------------------------------------------------------------------------ sources
def _md_escape(text: Any) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _table(rows: list[Mapping[str, Any]], columns: list[str]) -> str:
    head = "| " + " | ".join(_md_escape(c) for c in columns) + " |\n|" + "---|" * len(columns) + "\n"
    return head + "".join("| " + " | ".join(_md_escape(r.get(c, "")) for c in columns) + " |\n" for r in rows)


def _html(text: Any) -> str:
    import html

    return html.escape(str(text))


def _write_if_changed(path: Path, text: str | bytes) -> None:
    """Write only what changed, so that Sphinx reads again only the pages whose sources changed."""
    data = text.encode() if isinstance(text, str) else text
    if path.is_file() and path.read_bytes() == data:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def _about(name: str, notebooks_dir: Path) -> str:
    try:
        return read_manifest(notebooks_dir / f"{name}.py").about
    except (ManifestError, OSError):
        return ""


def _relative(target: Path, start: Path) -> str:
    return Path(os.path.relpath(target, start)).as_posix()


_NOTEBOOK_LINK = re.compile(r"\]\((\.\./)?notebooks/(\d\d_[A-Za-z0-9_]+)\.(py|ipynb)\)")


def _docs_page(text: str) -> str:
    """A docs page as the site shows it: links to a notebook's source go to its executed page."""
    return _NOTEBOOK_LINK.sub(lambda m: f"](../notebooks/{m.group(2)}.ipynb)", text)


def _index(
    layout: OutputLayout,
    summary: Mapping[str, Any],
    captions: Mapping[str, str],
    notebooks_dir: Path,
    published: OutputLayout | None = None,
) -> str:
    links = published or layout  # where readers find the run: the site links to its recordings from there
    notebooks = {nb["name"]: nb for nb in summary.get("notebooks", [])}
    quick = summary.get("quick")
    wall = summary.get("wall_time_s")
    n_figures = sum(1 for f in summary.get("figures_by_notebook", {}) if f.endswith(".png"))
    lines = [
        "# glu: gestures, language and affordances, reproduced",
        "",
        "A Python reproduction of Saponaro et al., *Interactive Robot Learning of Gestures, Language "
        "and Affordances* (GLU 2017) and its follow-up *Beyond the Self* (IEEE TCDS 2020): gesture "
        "HMMs, the Affordance–Words Bayesian network, their fusion, and verbal descriptions. This "
        "site is the record of one run of every notebook (`glu reproduce`): the executed notebooks, "
        "their figures, the comparison with the originals, and the API reference.",
        "",
        f"**Data:** {_md_escape(summary.get('data_source', 'unknown'))} · **mode:** "
        f"{'quick (small, fast runs)' if quick else 'full'}"
        + (f" · **wall time:** {wall:.1f} s" if wall is not None else "")
        + f" · {len(notebooks)} notebooks · {n_figures} figures",
        "",
        "## Ours against the originals",
        "",
    ]
    comparisons = [
        {**c, "max |ours − reference|": f"{c['max_abs_difference']:.3g}"}
        for c in summary.get("comparison_with_reference", [])
    ]
    if comparisons:
        lines += [
            "Each row compares a table of ours with the originals' model or the published values; the "
            "largest absolute difference over its numbers.",
            "",
            _table(comparisons, ["table", "reference", "rows", "max |ours − reference|"]),
        ]
    else:
        lines += [
            "No reference to compare with in this data (the originals' models come with the real data).",
            "",
        ]
    lines += ["## The notebooks", ""]
    rows = [
        {
            "notebook": f"[{name}](notebooks/{name}.ipynb)",
            "what it shows": _about(name, notebooks_dir),
            "status": n["status"],
            "seconds": n.get("seconds", ""),
            "parameters": parameters_text(n.get("parameters") or {}) or "defaults",
        }
        for name, n in sorted(notebooks.items())
    ]
    lines += [_table(rows, ["notebook", "what it shows", "status", "seconds", "parameters"]), ""]
    lines += [
        "## Figures",
        "",
        "Every figure of the run with its caption and the notebook that drew it; click one to see it at full "
        "size. Each is also saved as SVG beside the PNG (`figures/`).",
        "",
    ]
    by_notebook = summary.get("figures_by_notebook", {})
    shown = [
        (fname, nb)
        for fname, nb in sorted(by_notebook.items(), key=lambda item: (item[1], item[0]))
        if fname.endswith(".png") and (layout.figures / fname).is_file()
    ]
    lines += ["::::{container} glu-gallery"] if shown else ["This run drew no figures.", ""]
    for fname, nb in shown:
        caption = captions.get(fname, "")
        link = f"[{nb}](notebooks/{nb}.ipynb)" if nb in notebooks else nb
        lines += [
            f":::{{figure}} _figures/{fname}",
            f":alt: {fname[:-4]}",
            "",
            f"{caption} — `{fname[:-4]}`, {link}".strip(" —"),
            ":::",
        ]
    lines += ["::::", ""] if shown else []
    lines += ["## Recordings", ""]
    recordings = summary.get("recordings", [])
    if recordings:
        lines += [
            "Each anticipation and episode run is also a [Rerun](https://rerun.io) recording: the "
            "hand in 3-D, the HMM scores, the fused beliefs frame by frame. Open one in the Rerun "
            "viewer (installed with `glu[notebooks]`) from the output folder:",
            "",
            "```{raw} html",
            '<table class="table glu-recordings"><thead><tr><th>recording</th><th>notebook</th>'
            "<th>open it with</th></tr></thead><tbody>",
        ]
        by_nb = summary.get("recordings_by_notebook", {})
        for rec in recordings:
            target = _relative(links.recordings / rec, links.site)
            lines.append(
                f'<tr><td><a href="{_html(target)}">{_html(rec)}</a></td><td>{_html(by_nb.get(rec, ""))}</td>'
                f"<td><code>rerun recordings/{_html(rec)}</code></td></tr>"
            )
        lines += ["</tbody></table>", "```", ""]
    else:
        lines += ["This run wrote no recordings.", ""]
    versions = [{"package": k, "version": v} for k, v in summary.get("versions", {}).items()]
    lines += [
        "## Data and package versions",
        "",
        f"The data: {_md_escape(summary.get('data_source', 'unknown'))}. The real data is public (GPL) and "
        "is never copied into the repository: `glu data fetch` downloads it at the pinned commits and checks "
        "its checksums; without it the notebooks run on synthetic data of the same shape.",
        "",
        _table(versions, ["package", "version"]),
        "",
        "```{toctree}",
        ":hidden:",
        "",
        "notebooks",
        *(["docs"] if _docs_pages() else []),
        "api",
        "```",
        "",
    ]
    return "\n".join(lines)


def _checked(summary: Mapping[str, Any]) -> Mapping[str, Any]:
    """``summary`` when it is a run's summary whose every name is a plain file name; else :class:`SiteError`
    in one line saying what is wrong."""
    try:
        check_summary(summary)
    except SummaryError as e:
        raise SiteError(f"the run's summary.json {e}; run glu reproduce again") from None
    return summary


def read_summary(path: Path) -> Mapping[str, Any]:
    """The summary of the run at ``path`` (``results/summary.json``), checked; :class:`SiteError` in one
    line when it is missing, unreadable or malformed."""
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SiteError(
            f"no run to build the site from: {path.name} is missing in {path.parent.name}/ "
            "(run `glu reproduce` first)"
        ) from None
    except (OSError, ValueError) as e:
        raise SiteError(
            f"no run to build the site from: {path.name} in {path.parent.name}/ is not JSON ({e}); run "
            "`glu reproduce` again"
        ) from None
    return _checked(summary)


_NOTEBOOK_READ_ERRORS = (OSError, ValueError, KeyError, TypeError, AttributeError, IndexError, RecursionError)


def _read_executed(folder: Path, name: str) -> tuple[Any, dict[str, str]]:
    """The executed notebook ``folder/NAME.ipynb`` and its figures' captions; :class:`SiteError` in one line
    when it is missing, truncated, empty or not a valid notebook."""
    import nbformat

    ipynb = folder / f"{name}.ipynb"
    if not ipynb.is_file():
        raise SiteError(f"the executed notebook {name}.ipynb is missing from {folder.name}/")
    try:
        nb = nbformat.read(ipynb, as_version=4)
        nbformat.validate(nb)
        return nb, caption_figures(nb)
    except (*_NOTEBOOK_READ_ERRORS, nbformat.ValidationError) as e:
        why = str(e).splitlines()[0][:120] if str(e).strip() else type(e).__name__
        raise SiteError(
            f"the executed notebook {name}.ipynb in {folder.name}/ is not a readable notebook ({why}); "
            "run glu reproduce again"
        ) from None


def _docs_pages() -> list[Path]:
    return sorted(DOCS_DIR.glob("*.md")) if DOCS_DIR is not None and DOCS_DIR.is_dir() else []


_NOTEBOOKS_PAGE = """# Notebooks

The story, one notebook at a time, as `glu reproduce` executed them (nothing here is run again). Each runs
by hand in JupyterLab too (`make lab`), or headless with other parameters (`glu run NOTEBOOK -p NAME VALUE`).

```{toctree}
:glob:
:maxdepth: 1

notebooks/*
```
"""

_DOCS_PAGE = """# Documentation

```{toctree}
:glob:
:maxdepth: 1

docs/*
```
"""


def _api_page(modules: tuple[str, ...]) -> str:
    """The API page, in reStructuredText: autosummary generates its module pages only from ``.rst`` files."""
    body = "\n".join(f"   {m}" for m in modules)
    return f"""API reference
=============

glu's public modules, generated from their docstrings (numpydoc style). The command line (``glu --help``)
and the notebooks are built on these.

.. autosummary::
   :toctree: api

{body}
"""


def assemble(
    layout: OutputLayout,
    summary: Mapping[str, Any],
    source: Path,
    notebooks_dir: Path = paths.NOTEBOOKS_DIR,
    modules: tuple[str, ...] = API_MODULES,
    published: OutputLayout | None = None,
) -> dict[str, str]:
    """Write the site's sources into ``source``: the index, the executed notebooks of ``summary`` (their
    figures captioned), the docs pages, the API page, the figures of the gallery. Files that did not change
    are left untouched; files of pages no longer there are removed. Returns figure file → caption.

    ``summary`` is checked first (:func:`glu.run.summary.check_summary`): every name in it is a plain file
    name, so no page is ever written outside ``source``."""
    import nbformat

    summary = _checked(summary)
    names = [nb["name"] for nb in summary.get("notebooks", [])]
    keep: set[Path] = set()
    captions: dict[str, str] = {}
    for name in names:
        nb, figure_captions = _read_executed(layout.notebooks, name)
        captions.update(figure_captions)
        if not any(c.cell_type == "markdown" and c.source.lstrip().startswith("# ") for c in nb.cells):
            nb.cells.insert(0, nbformat.v4.new_markdown_cell(f"# {name}"))  # a page needs a title
        target = source / "notebooks" / f"{name}.ipynb"
        _write_if_changed(target, nbformat.writes(nb) + "\n")
        keep.add(target)
    for page in _docs_pages():
        target = source / "docs" / page.name
        _write_if_changed(target, _docs_page(page.read_text(encoding="utf-8")))
        keep.add(target)
    for fname, _ in summary.get("figures_by_notebook", {}).items():
        src = layout.figures / fname
        if fname.endswith(".png") and src.is_file():
            target = source / "_figures" / fname
            _write_if_changed(target, src.read_bytes())
            keep.add(target)
    pages = {
        "index.md": _index(layout, summary, captions, notebooks_dir, published),
        "notebooks.md": _NOTEBOOKS_PAGE,
        "api.rst": _api_page(modules),
    }
    if _docs_pages():
        pages["docs.md"] = _DOCS_PAGE
    for page, text in pages.items():
        _write_if_changed(source / page, text)
        keep.add(source / page)
    for stale in ("api.md",):
        (source / stale).unlink(missing_ok=True)
    for folder in ("notebooks", "docs", "_figures"):  # pages and figures of an earlier run, gone
        for f in (source / folder).glob("*") if (source / folder).is_dir() else []:
            if f not in keep:
                f.unlink()
    return captions


# ------------------------------------------------------------------------------------------ build
def _sphinx(source: Path, html: Path, doctrees: Path) -> tuple[int, str]:
    """Build ``source`` into ``html`` with Sphinx (every warning an error); (status, warnings).
    MyST-NB keeps its copies of the notebooks beside ``html`` (``jupyter_execute/``)."""
    from sphinx.application import Sphinx
    from sphinx.util.console import nocolor
    from sphinx.util.docutils import docutils_namespace, patch_docutils

    nocolor()
    warnings = io.StringIO()
    with patch_docutils(CONF_DIR), docutils_namespace():
        app = Sphinx(
            source,
            CONF_DIR,
            html,
            doctrees,
            "html",
            status=None,
            warning=warnings,
            warningiserror=True,
            keep_going=True,
        )
        app.build()
    return app.statuscode, warnings.getvalue()


def build_site(
    layout: OutputLayout,
    summary: Mapping[str, Any] | None = None,
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True),
    notebooks_dir: Path = paths.NOTEBOOKS_DIR,
    modules: tuple[str, ...] = API_MODULES,
    work: Path | None = None,
    published: OutputLayout | None = None,
) -> Path:
    """Build the site of the run in ``layout`` (its ``summary``; default: its ``results/summary.json``) into
    the folder ``layout.site``, which must not exist yet (a run being staged: :mod:`glu.run.publish`
    publishes it with the rest of the run); returns its ``index.html``. Raises :class:`SiteError` on any
    Sphinx warning, writing nothing into ``layout``.

    ``work`` keeps the sources and Sphinx's doctrees between builds (default: ``site-source/`` in the
    store); ``published`` is the layout readers will see the run in (links between the site and the
    recordings are relative to it; default: ``layout``)."""
    t0 = time.perf_counter()
    if summary is None:
        summary = read_summary(layout.results / "summary.json")
    if layout.site.exists() or layout.site.is_symlink():
        raise SiteError(f"{layout.site} exists; the site is built into a run being staged (glu.run.publish)")
    work = work if work is not None else layout.store / "site-source"
    source, html = work / "src", work / "html"
    source.mkdir(parents=True, exist_ok=True)
    assemble(layout, summary, source, notebooks_dir, modules, published=published)
    shutil.rmtree(
        html, ignore_errors=True
    )  # every page written afresh (from the doctrees kept): no stale page
    status, warnings = _sphinx(source, html, work / "doctrees")
    problems = [line for line in warnings.splitlines() if "WARNING" in line or "ERROR" in line]
    if status or problems:
        shown = "\n".join(_strip_paths(line, work) for line in problems[:20])
        raise SiteError(
            f"the documentation site was not built: {len(problems)} Sphinx warning(s) (every warning is an "
            f"error):\n{shown}"
        )
    staged = layout.site.with_name(f".{layout.site.name}.partial")
    shutil.rmtree(staged, ignore_errors=True)
    shutil.copytree(
        html,
        staged,
        ignore=shutil.ignore_patterns(".buildinfo", ".doctrees", "objects.inv", "webpack-macros.html"),
    )
    os.replace(staged, layout.site)
    index = layout.site / "index.html"
    pages = len(list(layout.site.rglob("*.html")))
    shown = (published or layout).site / index.name
    log(f"glu site: {pages} pages in {time.perf_counter() - t0:.1f} s: {shown}")
    return index


def _strip_paths(line: str, work: Path) -> str:
    """A warning line without the machine's paths (the site's sources, the package's folder)."""
    line = line.replace(f"{work}{os.sep}src{os.sep}", "")
    return line.replace(f"{paths.PACKAGE_DIR.parent}{os.sep}", "")


def main(argv: list[str] | None = None) -> int:
    """``python -m glu.run.site [--out DIR]`` (``make docs``): build the site of the published run again and
    publish the run with it (:func:`glu.run.publish.republish`: a new run folder, the same files, one
    rename)."""
    import argparse

    from glu.run.lock import run_lock
    from glu.run.publish import republish

    parser = argparse.ArgumentParser(
        prog="python -m glu.run.site",
        description="Build the documentation site from the last glu reproduce run.",
    )
    parser.add_argument("-o", "--out", type=Path, help="the run's output folder (default: the project's)")
    args = parser.parse_args(argv)
    try:
        layout = OutputLayout.at(args.out)
        with run_lock(layout.root):
            republish(layout, "site", lambda staged, work: build_site(staged, work=work, published=layout))
    except GluError as e:
        print(f"glu site: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
