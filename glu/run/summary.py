"""What a run of the notebooks leaves behind: each notebook's result, ``results/summary.json`` and
``summary.csv``, and the record of how the figures were rendered.

:func:`write_summary` collects every result table of a run (with the data source, the package versions,
each notebook's time and non-default parameters, and the comparisons with a reference) and writes them:
it is :func:`collect_summary` then :func:`save_summary` (with :func:`summary_csv`, the long format), which
:func:`glu.run.reproduce.reproduce` calls apart, so that the wall time it records covers the report too.
:func:`expected_seconds` says how long each notebook should take (the last run's times, else what the
notebook declares, :func:`declared_seconds`), so that :func:`glu.run.reproduce.run_order` can start the
longest first. ``figures/rendered-with.json`` (:func:`write_rendering_record`) says which data and which
renderer versions the committed figures come from.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from glu.errors import GluError, OutputError
from glu.files import atomic_write_text, plain_name
from glu.paths import OutputLayout
from glu.run.manifest import read_manifest


class SummaryError(GluError):
    """A ``summary.json`` that is not a run's summary (a field missing, of the wrong type, or a name that is
    not a plain file name)."""


def _number(v: Any, finite: bool = True) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and (math.isfinite(v) or not finite)


def _names_of(value: Any, where: str, mapping: bool = False) -> None:
    if value is None:
        return
    if mapping and not isinstance(value, dict) or not mapping and not isinstance(value, list):
        raise SummaryError(
            f"{where}: expected a {'mapping' if mapping else 'list'}, got {type(value).__name__}"
        )
    for name in value:
        if not plain_name(name):
            raise SummaryError(f"{where}: {name!r} is not a plain file name")
        if mapping and not plain_name(value[name]):
            raise SummaryError(f"{where}[{name!r}]: {value[name]!r} is not a notebook's name")


def check_summary(doc: Any) -> None:
    """:class:`SummaryError` (naming the field) unless ``doc`` is a run's summary as
    :func:`collect_summary` writes it: every notebook, figure and recording a plain file name
    (:func:`glu.files.plain_name`), so that none can become a path outside the run's folders."""
    if not isinstance(doc, dict):
        raise SummaryError(f"is not a run's summary (a JSON {type(doc).__name__}, not an object)")
    notebooks = doc.get("notebooks")
    if not isinstance(notebooks, list):
        raise SummaryError("has no list of notebooks")
    for i, nb in enumerate(notebooks):
        if not isinstance(nb, dict) or not plain_name(nb.get("name")):
            raise SummaryError(
                f"notebooks[{i}]: {nb.get('name') if isinstance(nb, dict) else nb!r} is not a notebook's name"
            )
        if not isinstance(nb.get("status", ""), str) or not isinstance(nb.get("parameters") or {}, dict):
            raise SummaryError(f"notebooks[{i}] ({nb['name']}): status or parameters of the wrong type")
        if "seconds" in nb and not _number(nb["seconds"]):
            raise SummaryError(f"notebooks[{i}] ({nb['name']}): seconds is not a number")
    _names_of(doc.get("figures"), "figures")
    _names_of(doc.get("figures_by_notebook"), "figures_by_notebook", mapping=True)
    _names_of(doc.get("recordings"), "recordings")
    _names_of(doc.get("recordings_by_notebook"), "recordings_by_notebook", mapping=True)
    for key, kind in (("data_source", str), ("quick", bool), ("versions", dict), ("tables", dict)):
        if key in doc and not isinstance(doc[key], kind):
            raise SummaryError(f"{key}: expected {kind.__name__}, got {type(doc[key]).__name__}")
    for name, table in (doc.get("tables") or {}).items():
        if not isinstance(table, dict) or not isinstance(table.get("meta"), dict):
            raise SummaryError(f"tables[{name!r}]: not a table (its meta and rows)")
    if doc.get("wall_time_s") is not None and not _number(doc["wall_time_s"]):
        raise SummaryError("wall_time_s is not a number")
    for i, c in enumerate(doc.get("comparison_with_reference") or []):
        ok = isinstance(c, dict) and isinstance(c.get("table"), str) and isinstance(c.get("reference"), str)
        if not ok or not _number(c.get("rows")) or not _number(c.get("max_abs_difference"), False):
            raise SummaryError(
                f"comparison_with_reference[{i}] is not a comparison (table, reference, rows, "
                "max_abs_difference)"
            )


@dataclass
class NotebookResult:
    """What happened to one notebook: ``status`` is ``ok`` or ``failed``."""

    name: str
    status: str
    seconds: float
    executed: Path | None = None
    error: str = ""
    files: list[str] = field(default_factory=list)
    parameters: dict[str, Any] = field(default_factory=dict)


def declared_seconds(notebook: str | os.PathLike) -> float | None:
    """The seconds a notebook declares a full run takes, or None: ``expected_seconds`` in its manifest
    (:func:`glu.run.manifest.read_manifest`; None too when it has no readable manifest)::

        # jupyter:
        #   glu:
        #     expected_seconds: 30

    A rough hint, for the order of a first run (:func:`expected_seconds`); a run's own times replace it.
    """
    try:
        return read_manifest(notebook).expected_seconds
    except (OSError, ValueError, AttributeError):  # ValueError: not UTF-8, or a ManifestError
        return None


def previous_summary(results_dir: Path) -> dict[str, Any]:
    """The ``summary.json`` in ``results_dir``; {} when there is none, or one that is not a JSON object."""
    try:
        doc = json.loads((results_dir / "summary.json").read_text())
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


def _last_run_seconds(layout: OutputLayout, quick: bool) -> dict[str, float]:
    """Each notebook's time in the last run in the same mode (``quick`` or full): this output's summary,
    else the project's; {} if none."""
    folders = [layout.results]
    try:
        folders.append(OutputLayout.at(None).results)
    except OutputError:  # an installed package has no project folders
        pass
    for folder in dict.fromkeys(folders):
        doc = previous_summary(folder)
        try:
            if bool(doc["quick"]) != quick:  # a quick run's times say little about a full run's
                continue
            return {nb["name"]: float(nb["seconds"]) for nb in doc["notebooks"]}
        except (ValueError, KeyError, TypeError):
            continue
    return {}


def expected_seconds(
    layout: OutputLayout, notebooks: Iterable[Path] = (), quick: bool = False
) -> dict[str, float]:
    """How long each notebook should take, by name: its time in the last run in the same mode
    (``results/summary.json`` of ``layout``, else the project's own), else, for those of ``notebooks`` the
    last run did not time (a first run: a fresh clone, a new ``--out`` folder), the time it declares
    (:func:`declared_seconds`). Notebooks with neither are left out.
    """
    timed = _last_run_seconds(layout, quick)
    declared = {nb.stem: declared_seconds(nb) for nb in notebooks if nb.stem not in timed}
    return {**{k: v for k, v in declared.items() if v is not None}, **timed}


RENDERING_RECORD = "rendered-with.json"
"""In ``figures/``: the data and the library versions the figures were rendered with (no timestamps)."""


def rendering_versions() -> dict[str, str]:
    """The versions that decide a figure's bytes: matplotlib and the FreeType it renders text with."""
    import matplotlib
    from matplotlib import ft2font

    return {"matplotlib": matplotlib.__version__, "freetype": ft2font.__freetype_version__}


def write_rendering_record(figures_dir: Path, data: str, quick: bool, made_by: str = "") -> Path:
    """Write ``figures/rendered-with.json``: which data, which mode, which glu (``made_by``: version and
    commit, :mod:`glu.run.provenance`), which renderer versions."""
    record = {"data_source": data, "quick": quick, **({"made_by": made_by} if made_by else {})}
    record.update(rendering_versions())
    path = figures_dir / RENDERING_RECORD
    figures_dir.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, json.dumps(record, indent=1, sort_keys=True) + "\n")
    return path


def write_summary(
    results_dir: Path, runs: list[NotebookResult], data: str, quick: bool, wall: float
) -> dict[str, Any]:
    """Collect every result table into ``summary.json`` and a long-format ``summary.csv``, with ``wall``
    (seconds) as the run's wall time: :func:`collect_summary`, then :func:`save_summary`; returns the
    summary."""
    summary = collect_summary(results_dir, runs, data, quick)
    summary["wall_time_s"] = round(wall, 3)
    save_summary(results_dir, summary)
    return summary


def collect_summary(
    results_dir: Path,
    runs: list[NotebookResult],
    data: str,
    quick: bool,
    previous: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The summary of a run whose result tables are in ``results_dir`` (nothing is written); its
    ``wall_time_s`` is None until the caller sets it.

    A partial run (``--only``) updates the ``previous`` summary (default: ``results_dir/summary.json``) when
    it was made from the same data in the same mode: the notebooks just run replace their earlier entries,
    the others are kept.
    """
    from glu.run.outputs import package_versions

    notebooks = {
        r.name: dict(name=r.name, status=r.status, seconds=round(r.seconds, 3), parameters=r.parameters)
        for r in runs
    }
    entries: dict[str, dict[str, Any]] = {"tables": {}, "figures": {}, "recordings": {}}
    old = previous_summary(results_dir) if previous is None else previous
    if old.get("data_source") == data and old.get("quick") == quick:
        _keep_previous(old, notebooks, entries)
    for run in runs:
        for f in run.files:
            p = Path(f)
            if p.suffix == ".json" and p.parent == results_dir:
                doc = json.loads(p.read_text())
                entries["tables"][doc["meta"]["name"]] = doc
            elif p.parent.name == "figures":
                entries["figures"][p.name] = run.name
            elif p.suffix == ".rrd":
                entries["recordings"][p.name] = run.name
    tables, figures, recordings = entries["tables"], entries["figures"], entries["recordings"]
    return {
        "ran": [r.name for r in runs],
        "data_source": data,
        "quick": quick,
        "wall_time_s": None,
        "versions": package_versions(),
        "notebooks": [notebooks[k] for k in sorted(notebooks)],
        "figures": sorted(figures),
        "figures_by_notebook": dict(sorted(figures.items())),
        "recordings": sorted(recordings),
        "recordings_by_notebook": dict(sorted(recordings.items())),
        "comparison_with_reference": _comparisons(tables),
        "tables": {k: tables[k] for k in sorted(tables)},
    }


def _keep_previous(
    old: Mapping[str, Any], notebooks: dict[str, Any], entries: dict[str, dict[str, Any]]
) -> None:
    """Add to ``notebooks`` and ``entries`` the previous summary's notebooks that this run did not run,
    with their tables, figures and recordings."""
    for nb in old.get("notebooks", []):
        name = nb["name"]
        if name in notebooks:
            continue
        notebooks[name] = nb
        entries["tables"].update(
            {k: v for k, v in old.get("tables", {}).items() if v["meta"].get("notebook") == name}
        )
        for kind in ("figures", "recordings"):
            by_notebook = old.get(f"{kind}_by_notebook", {})
            entries[kind].update({f: name for f, n in by_notebook.items() if n == name})


def _comparisons(tables: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The tables that declare a reference and have a ``difference`` column: the largest |difference|."""
    import pandas as pd

    comparison = []
    for name in sorted(tables):
        df = pd.DataFrame(tables[name]["rows"])
        meta = tables[name]["meta"]
        reference = meta.get("reference") or (meta.get("parameters") or {}).get("reference")
        if reference and "difference" in df.columns and len(df):  # a comparison names its reference
            diff = pd.to_numeric(df["difference"], errors="coerce").abs()
            comparison.append(
                {
                    "table": name,
                    "reference": reference,
                    "rows": int(diff.notna().sum()),
                    "max_abs_difference": float(diff.max()),
                }
            )
    return comparison


def summary_csv(summary: dict[str, Any]) -> str:
    """Every number of the tables of ``summary`` (:func:`collect_summary`) in long format, as the text of
    ``summary.csv``: one row per table cell (table, row, column, value).

    Each cell's value is the element of ``DataFrame(rows).values`` (the frame's common dtype: an all-numeric
    table gives floats, a mixed one the values as they are), which is what ``DataFrame.iterrows`` yields,
    taken row by row without building a Series per row (about 0.9 s → 0.3 s on the real data's 6 MB)."""
    import numpy as np
    import pandas as pd

    tables, rows, columns, values = [], [], [], []
    for name, table in summary["tables"].items():
        df = pd.DataFrame(table["rows"])
        if df.empty:
            continue
        cells = df.values
        n, m = cells.shape
        tables.append(np.full(n * m, name, dtype=object))
        rows.append(np.repeat(np.asarray(df.index), m))
        columns.append(np.tile(np.asarray(df.columns, dtype=object), n))
        values.extend(cells.ravel().tolist())
    # one frame, so that pandas infers the value column's type over every table at once, as it did
    frame = pd.DataFrame([])
    if tables:
        parts = {"table": tables, "row": rows, "column": columns}
        frame = pd.DataFrame({**{k: np.concatenate(v) for k, v in parts.items()}, "value": values})
    return frame.to_csv(index=False, lineterminator="\n")


def save_summary(results_dir: Path, summary: dict[str, Any], csv: str | None = None) -> Path:
    """Write ``summary`` (:func:`collect_summary`) to ``summary.json`` and its numbers to ``summary.csv``
    (``csv``, the text of :func:`summary_csv`, computed here if not given); returns ``summary.json``."""
    results_dir.mkdir(parents=True, exist_ok=True)
    path = results_dir / "summary.json"
    atomic_write_text(path, json.dumps(summary, indent=1, default=str) + "\n")
    atomic_write_text(results_dir / "summary.csv", summary_csv(summary) if csv is None else csv)
    return path
