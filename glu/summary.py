"""What a run of the notebooks leaves behind: each notebook's result, ``results/summary.json`` and
``summary.csv``, and the record of how the figures were rendered.

:func:`write_summary` collects every result table of a run (with the data source, the package versions,
each notebook's time and non-default parameters, and the comparisons with a reference);
:func:`expected_seconds` reads the notebooks' times back, so that :func:`glu.reproduce.reproduce` can
start the longest first. ``figures/rendered-with.json`` (:func:`write_rendering_record`) says which data
and which renderer versions the committed figures come from.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from glu.files import atomic_write_text
from glu.paths import OutputLayout


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


def expected_seconds(layout: OutputLayout) -> dict[str, float]:
    """How long each notebook took in the last run (this output's summary, else the project's); {} if none."""
    for folder in dict.fromkeys((layout.results, OutputLayout.at(None).results)):
        try:
            doc = json.loads((folder / "summary.json").read_text())
            return {nb["name"]: float(nb["seconds"]) for nb in doc["notebooks"]}
        except (OSError, ValueError, KeyError, TypeError):
            continue
    return {}


RENDERING_RECORD = "rendered-with.json"
"""In ``figures/``: the data and the library versions the figures were rendered with (no timestamps)."""


def rendering_versions() -> dict[str, str]:
    """The versions that decide a figure's bytes: matplotlib and the FreeType it renders text with."""
    import matplotlib
    from matplotlib import ft2font

    return {"matplotlib": matplotlib.__version__, "freetype": ft2font.__freetype_version__}


def write_rendering_record(figures_dir: Path, data: str, quick: bool) -> Path:
    """Write ``figures/rendered-with.json``: which data, which mode, which renderer versions."""
    record = {"data_source": data, "quick": quick, **rendering_versions()}
    path = figures_dir / RENDERING_RECORD
    figures_dir.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, json.dumps(record, indent=1, sort_keys=True) + "\n")
    return path


def write_summary(
    results_dir: Path, runs: list[NotebookResult], data: str, quick: bool, wall: float
) -> dict[str, Any]:
    """Collect every result table into ``summary.json`` and a long-format ``summary.csv``.

    A partial run (``--only``) updates the existing summary when it was made from the same data in the
    same mode: the notebooks just run replace their earlier entries, the others are kept.
    """
    import pandas as pd

    from glu.outputs import package_versions

    notebooks = {
        r.name: {
            "name": r.name,
            "status": r.status,
            "seconds": round(r.seconds, 3),
            "parameters": r.parameters,
        }
        for r in runs
    }
    tables: dict[str, Any] = {}
    figures: dict[str, str] = {}
    recordings: dict[str, str] = {}
    previous = results_dir / "summary.json"
    if previous.is_file():
        try:
            old = json.loads(previous.read_text())
        except (OSError, json.JSONDecodeError):
            old = {}
        if old.get("data_source") == data and old.get("quick") == quick:
            for nb in old.get("notebooks", []):
                if nb["name"] not in notebooks:
                    notebooks[nb["name"]] = nb
                    tables.update(
                        {
                            k: v
                            for k, v in old.get("tables", {}).items()
                            if v["meta"].get("notebook") == nb["name"]
                        }
                    )
                    figures.update(
                        {
                            f: nb["name"]
                            for f, n in old.get("figures_by_notebook", {}).items()
                            if n == nb["name"]
                        }
                    )
                    recordings.update(
                        {
                            f: nb["name"]
                            for f, n in old.get("recordings_by_notebook", {}).items()
                            if n == nb["name"]
                        }
                    )
    for run in runs:
        for f in run.files:
            p = Path(f)
            if p.suffix == ".json" and p.parent == results_dir:
                doc = json.loads(p.read_text())
                tables[doc["meta"]["name"]] = doc
            elif p.parent.name == "figures":
                figures[p.name] = run.name
            elif p.suffix == ".rrd":
                recordings[p.name] = run.name
    long_rows, comparison = [], []
    for name in sorted(tables):
        df = pd.DataFrame(tables[name]["rows"])
        for i, row in df.iterrows():
            for col, val in row.items():
                long_rows.append({"table": name, "row": i, "column": col, "value": val})
        meta = tables[name]["meta"]
        reference = meta.get("reference") or (meta.get("parameters") or {}).get("reference")
        if (
            reference and "difference" in df.columns and len(df)
        ):  # a comparison declares what it compares with
            diff = pd.to_numeric(df["difference"], errors="coerce").abs()
            comparison.append({"table": name, "reference": reference, "rows": int(diff.notna().sum()),
                               "max_abs_difference": float(diff.max())})  # fmt: skip
    summary = {
        "ran": [r.name for r in runs],
        "data_source": data,
        "quick": quick,
        "wall_time_s": round(wall, 3),
        "versions": package_versions(),
        "notebooks": [notebooks[k] for k in sorted(notebooks)],
        "figures": sorted(figures),
        "figures_by_notebook": dict(sorted(figures.items())),
        "recordings": sorted(recordings),
        "recordings_by_notebook": dict(sorted(recordings.items())),
        "comparison_with_reference": comparison,
        "tables": {k: tables[k] for k in sorted(tables)},
    }
    results_dir.mkdir(parents=True, exist_ok=True)
    atomic_write_text(previous, json.dumps(summary, indent=1, default=str) + "\n")
    atomic_write_text(
        results_dir / "summary.csv", pd.DataFrame(long_rows).to_csv(index=False, lineterminator="\n")
    )
    return summary
