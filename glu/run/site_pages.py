"""What the site's own pages say: the index of a run, the notebooks' page and the docs' page, in Markdown.

:mod:`glu.run.site` assembles them with the executed notebooks, the docs pages and the API reference
(:mod:`glu.run.site_api`), and builds the site. The index is written section by section from the run's
``results/summary.json``: the run (its data, its mode, the commit of glu that made it), ours against the
originals, the notebooks, the figures with their captions, the recordings, the data and the versions.
The docs pages are listed in the order the README's "Documentation" section gives them: its reading
order, not their file names'.
"""

from __future__ import annotations

import html
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from glu.paths import OutputLayout
from glu.run.manifest import ManifestError, read_manifest
from glu.run.outputs import parameters_text


def md_escape(text: Any) -> str:
    """Text for a cell of a Markdown table (its pipes escaped, on one line)."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def md_table(rows: list[Mapping[str, Any]], columns: list[str]) -> str:
    """A Markdown table of ``rows`` (mappings), one column per name in ``columns``."""
    head = "| " + " | ".join(md_escape(c) for c in columns) + " |\n|" + "---|" * len(columns) + "\n"
    return head + "".join("| " + " | ".join(md_escape(r.get(c, "")) for c in columns) + " |\n" for r in rows)


def _about(name: str, notebooks_dir: Path) -> str:
    try:
        return read_manifest(notebooks_dir / f"{name}.py").about
    except (ManifestError, OSError):
        return ""


_NOTEBOOK_LINK = re.compile(r"\]\((\.\./)?notebooks/(\d\d_[A-Za-z0-9_]+)\.(py|ipynb)\)")


def docs_page(text: str) -> str:
    """A docs page as the site shows it: links to a notebook's source go to its executed page."""
    return _NOTEBOOK_LINK.sub(lambda m: f"](../notebooks/{m.group(2)}.ipynb)", text)


# ------------------------------------------------------------------------------------------ the index
INTRO = (
    "A Python reproduction of Saponaro et al., *Interactive Robot Learning of Gestures, Language and "
    "Affordances* (GLU 2017) and its follow-up *Beyond the Self* (IEEE TCDS 2020): gesture HMMs, the "
    "Affordance–Words Bayesian network, their fusion, and verbal descriptions. This site is the record of "
    "one run of every notebook (`glu reproduce`): the executed notebooks, their figures, the comparison "
    "with the originals, and the API reference."
)


def _head(summary: Mapping[str, Any]) -> list[str]:
    """The title, what glu is, and one line naming the run: its data, mode, time, size and glu's version."""
    quick, wall = summary.get("quick"), summary.get("wall_time_s")
    n_notebooks = len(summary.get("notebooks", []))
    n_figures = sum(1 for f in summary.get("figures_by_notebook", {}) if f.endswith(".png"))
    run = (
        f"**Data:** {md_escape(summary.get('data_source', 'unknown'))} · **mode:** "
        f"{'quick (small, fast runs)' if quick else 'full'}"
        + (f" · **wall time:** {wall:.1f} s" if wall is not None else "")
        + f" · {n_notebooks} notebooks · {n_figures} figures"
        + (f" · **made by:** {md_escape(summary['made_by'])}" if summary.get("made_by") else "")
    )
    return ["# glu: gestures, language and affordances, reproduced", "", INTRO, "", run, ""]


def _comparisons(summary: Mapping[str, Any]) -> list[str]:
    lines = ["## Ours against the originals", ""]
    rows = [
        {**c, "max |ours − reference|": f"{c['max_abs_difference']:.3g}"}
        for c in summary.get("comparison_with_reference", [])
    ]
    if not rows:
        return lines + [
            "No reference to compare with in this data (the originals' models come with the real data).",
            "",
        ]
    return lines + [
        "Each row compares a table of ours with the originals' model or the published values; the "
        "largest absolute difference over its numbers.",
        "",
        md_table(rows, ["table", "reference", "rows", "max |ours − reference|"]),
    ]


def _notebooks(summary: Mapping[str, Any], notebooks_dir: Path) -> list[str]:
    notebooks = {nb["name"]: nb for nb in summary.get("notebooks", [])}
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
    columns = ["notebook", "what it shows", "status", "seconds", "parameters"]
    return ["## The notebooks", "", md_table(rows, columns), ""]


def _gallery(layout: OutputLayout, summary: Mapping[str, Any], captions: Mapping[str, str]) -> list[str]:
    """Every figure of the run, by notebook, each with its caption, its file and its notebook."""
    lines = [
        "## Figures",
        "",
        "Every figure of the run with its caption and the notebook that drew it; click one to see it at full "
        "size. Each is also saved as SVG beside the PNG (`figures/`).",
        "",
    ]
    ran = {nb["name"] for nb in summary.get("notebooks", [])}
    shown = [
        (fname, nb)
        for fname, nb in sorted(summary.get("figures_by_notebook", {}).items(), key=lambda i: (i[1], i[0]))
        if fname.endswith(".png") and (layout.figures / fname).is_file()
    ]
    if not shown:
        return lines + ["This run drew no figures.", ""]
    lines.append("::::{container} glu-gallery")
    for fname, nb in shown:
        link = f"[{nb}](notebooks/{nb}.ipynb)" if nb in ran else nb
        lines += [
            f":::{{figure}} _figures/{fname}",
            f":alt: {fname[:-4]}",
            "",
            f"{captions.get(fname, '')} [`{fname}` · {link}]{{.glu-file}}".strip(),
            ":::",
        ]
    return lines + ["::::", ""]


def _recordings(layout: OutputLayout, summary: Mapping[str, Any]) -> list[str]:
    """The run's Rerun recordings, each with its notebook and the command that opens it (``layout``: where
    readers find the run; the links are relative to its site)."""
    recordings = summary.get("recordings", [])
    if not recordings:
        return ["## Recordings", "", "This run wrote no recordings.", ""]
    lines = [
        "## Recordings",
        "",
        "Each anticipation and episode run is also a [Rerun](https://rerun.io) recording: the hand in 3-D, "
        "the HMM scores, the fused beliefs frame by frame. Open one in the Rerun viewer (installed with "
        "`glu[notebooks]`) from the output folder:",
        "",
        "```{raw} html",
        '<table class="table glu-recordings"><thead><tr><th>recording</th><th>notebook</th>'
        "<th>open it with</th></tr></thead><tbody>",
    ]
    by_nb = summary.get("recordings_by_notebook", {})
    for rec in recordings:
        target = html.escape(Path(os.path.relpath(layout.recordings / rec, layout.site)).as_posix())
        name = html.escape(rec)
        lines.append(
            f'<tr><td><a href="{target}">{name}</a></td><td>{html.escape(by_nb.get(rec, ""))}</td>'
            f"<td><code>rerun recordings/{name}</code></td></tr>"
        )
    return lines + ["</tbody></table>", "```", ""]


def _versions(summary: Mapping[str, Any], has_docs: bool) -> list[str]:
    """The data, the versions of the packages behind the results, and the site's table of contents."""
    versions = [{"package": k, "version": v} for k, v in summary.get("versions", {}).items()]
    return [
        "## Data and package versions",
        "",
        f"The data: {md_escape(summary.get('data_source', 'unknown'))}. The real data is public (GPL) and "
        "is never copied into the repository: `glu data fetch` downloads it at the pinned commits and checks "
        "its checksums; without it the notebooks run on synthetic data of the same shape.",
        "",
        md_table(versions, ["package", "version"]),
        "",
        "```{toctree}",
        ":hidden:",
        "",
        "notebooks",
        *(["docs"] if has_docs else []),
        "api",
        "```",
        "",
    ]


def index_page(
    layout: OutputLayout,
    summary: Mapping[str, Any],
    captions: Mapping[str, str],
    notebooks_dir: Path,
    has_docs: bool,
    published: OutputLayout | None = None,
) -> str:
    """The site's front page, from the run's summary and the figures' captions (``published``: the layout
    readers will see the run in, which the links to the recordings are relative to; default ``layout``)."""
    return "\n".join(
        _head(summary)
        + _comparisons(summary)
        + _notebooks(summary, notebooks_dir)
        + _gallery(layout, summary, captions)
        + _recordings(published or layout, summary)
        + _versions(summary, has_docs)
    )


# ------------------------------------------------------------------------------------------ sections
NOTEBOOKS_PAGE = """# Notebooks

The story, one notebook at a time, as `glu reproduce` executed them (nothing here is run again). Each runs
by hand in JupyterLab too (`make lab`), or headless with other parameters (`glu run NOTEBOOK -p NAME VALUE`).

```{toctree}
:glob:
:maxdepth: 1

notebooks/*
```
"""

_DOCS_LINK = re.compile(r"\]\(docs/([A-Za-z0-9_-]+)\.md[)#]")


def reading_order(names: list[str], readme: str) -> list[str]:
    """The docs pages ``names`` (file stems) in the order the README's "Documentation" section links them;
    pages it does not link come after, by name."""
    section = readme.partition("\n## Documentation\n")[2].partition("\n## ")[0]
    linked = list(dict.fromkeys(m.group(1) for m in _DOCS_LINK.finditer(section)))
    return [n for n in linked if n in names] + sorted(n for n in names if n not in linked)


def docs_index_page(order: list[str]) -> str:
    """The Documentation page: its toctree lists the docs pages in ``order``."""
    entries = "\n".join(f"docs/{name}" for name in order)
    return f"# Documentation\n\n```{{toctree}}\n:maxdepth: 1\n\n{entries}\n```\n"
