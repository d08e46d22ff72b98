"""The documentation site of a run: the executed notebooks, the docs pages and the API reference, with Sphinx.

``glu reproduce`` ends with :func:`build_site`, which writes the layout's ``site/`` folder (``build/site/`` in
a checkout, ``OUT/site/`` with ``--out``); ``make docs`` (``python -m glu.run.site``) builds it again from the
last run. The site is made with the tools of the scientific Python ecosystem's notebook collections: Sphinx,
MyST-NB (the stack of Jupyter Book 1) and the PyData theme. It holds

* the **index** (:mod:`glu.run.site_pages`): the run (its data, and the commit of glu that made it), the
  comparison of our numbers with the originals', every figure with its caption and its notebook, the
  notebooks with their times and parameters, the Rerun recordings with the command that opens them, and the
  package versions;
* each **executed notebook** as a page, its outputs as ``glu reproduce`` executed them (MyST-NB's
  ``nb_execution_mode = "off"``: nothing runs again), each figure with its caption
  (:func:`glu.run.captions.caption_figures`);
* the **docs pages** of the checkout (``docs/*.md``), in the reading order of the README's "Documentation"
  section;
* the **API reference**: a page for every public module, found by walking the package, its cross-references
  linked (:mod:`glu.run.site_api`; autodoc, autosummary, napoleon);
* search (Sphinx's own, offline), formulas as MathML (:mod:`glu.run.site_math`). A click on any figure
  opens it at its natural size with its caption.

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
import shutil
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from glu import paths
from glu.errors import GluError
from glu.files import atomic_write_bytes
from glu.paths import OutputLayout
from glu.run.captions import caption_figures
from glu.run.site_api import api_modules, api_pages
from glu.run.site_pages import NOTEBOOKS_PAGE, docs_index_page, docs_page, index_page, reading_order
from glu.run.summary import SummaryError, check_summary

CONF_DIR: Path = paths.RESOURCES_DIR / "site"
"""Sphinx's configuration, static files and templates of the site (shipped with the package).

:meta hide-value:
"""

DOCS_DIR: Path | None = paths.PROJECT_ROOT / "docs" if paths.PROJECT_ROOT is not None else None
"""The checkout's docs pages (``docs/*.md``), or None for an installed package.

:meta hide-value:
"""


class SiteError(GluError):
    """The documentation site could not be built (a Sphinx warning or error, or no executed notebooks)."""


# ------------------------------------------------------------------------------------------ sources
def _write_if_changed(path: Path, text: str | bytes) -> Path:
    """Write only what changed, so that Sphinx reads again only the pages whose sources changed; returns
    ``path``."""
    data = text.encode() if isinstance(text, str) else text
    if not path.is_file() or path.read_bytes() != data:
        atomic_write_bytes(path, data)
    return path


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
    """The checkout's docs pages in reading order (:func:`glu.run.site_pages.reading_order`)."""
    if DOCS_DIR is None or not DOCS_DIR.is_dir():
        return []
    pages = {p.stem: p for p in DOCS_DIR.glob("*.md")}
    readme = DOCS_DIR.parent / "README.md"
    text = readme.read_text(encoding="utf-8") if readme.is_file() else ""
    return [pages[name] for name in reading_order(list(pages), text)]


def assemble(
    layout: OutputLayout,
    summary: Mapping[str, Any],
    source: Path,
    notebooks_dir: Path = paths.NOTEBOOKS_DIR,
    modules: tuple[str, ...] | None = None,
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
        keep.add(_write_if_changed(source / "notebooks" / f"{name}.ipynb", nbformat.writes(nb) + "\n"))
    docs = _docs_pages()
    for page in docs:
        keep.add(_write_if_changed(source / "docs" / page.name, docs_page(page.read_text(encoding="utf-8"))))
    for fname in summary.get("figures_by_notebook", {}):
        if fname.endswith(".png") and (layout.figures / fname).is_file():
            keep.add(_write_if_changed(source / "_figures" / fname, (layout.figures / fname).read_bytes()))
    pages = {
        "index.md": index_page(
            layout, summary, captions, notebooks_dir, has_docs=bool(docs), published=published
        ),
        "notebooks.md": NOTEBOOKS_PAGE,
        **api_pages(api_modules() if modules is None else modules),
    }
    if docs:
        pages["docs.md"] = docs_index_page([p.stem for p in docs])
    for page, text in pages.items():
        keep.add(_write_if_changed(source / page, text))
    (source / "api.md").unlink(missing_ok=True)  # it would clash with api.rst (one document, two files)
    for folder in ("notebooks", "docs", "_figures", "api"):  # pages and figures of an earlier run, gone
        for f in (source / folder).glob("*") if (source / folder).is_dir() else []:
            if f not in keep:
                f.unlink()
    return captions


# ------------------------------------------------------------------------------------------ build
def _sphinx(
    source: Path, html: Path, doctrees: Path, modules: tuple[str, ...] | None = None
) -> tuple[int, str]:
    """Build ``source`` into ``html`` with Sphinx (every warning an error); (status, warnings).
    MyST-NB keeps its copies of the notebooks beside ``html`` (``jupyter_execute/``). ``modules``: the
    modules of the API reference when it holds only some (references to the others then need no page)."""
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
            confoverrides={"glu_api_modules": modules} if modules is not None else {},
        )
        app.build()
    return app.statuscode, warnings.getvalue()


def build_site(
    layout: OutputLayout,
    summary: Mapping[str, Any] | None = None,
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True),
    notebooks_dir: Path = paths.NOTEBOOKS_DIR,
    modules: tuple[str, ...] | None = None,
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
    modules = api_modules() if modules is None else modules
    assemble(layout, summary, source, notebooks_dir, modules, published=published)
    shutil.rmtree(
        html, ignore_errors=True
    )  # every page written afresh (from the doctrees kept): no stale page
    status, warnings = _sphinx(source, html, work / "doctrees", modules)
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
