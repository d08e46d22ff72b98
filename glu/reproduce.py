"""Run every notebook headless with papermill: figures, recordings, result tables and a summary.

``glu reproduce`` (and ``make reproduce``) calls :func:`reproduce`. Each notebook runs in its own kernel,
writing into a private staging folder; when it succeeds its files are moved into the folders of the
output layout (:class:`glu.paths.OutputLayout`: ``figures/``, ``recordings/``, ``results/``, ``models/``,
the executed notebook into ``build/notebooks/``; or all under ``--out``).
A failing notebook stops the run with a message naming the notebook and the cell, keeps its executed copy
(``NAME.failed.ipynb``), and leaves the outputs of earlier runs as they were. At the end
``results/summary.json`` and ``results/summary.csv`` collect every number behind every figure, the data
source, the package versions and the comparison with the original model.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
import uuid
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from glu import paths
from glu.data.source import resolve_data
from glu.errors import GluError
from glu.files import atomic_write_text
from glu.paths import OutputLayout


class NotebookError(GluError):
    """A notebook failed while running."""


@dataclass
class NotebookResult:
    """What happened to one notebook: ``status`` is ``ok`` or ``failed``."""

    name: str
    status: str
    seconds: float
    executed: Path | None = None
    error: str = ""
    files: list[str] = field(default_factory=list)


def list_notebooks(only: Sequence[str] | None = None, folder: Path = paths.NOTEBOOKS_DIR) -> list[Path]:
    """The notebooks (jupytext ``NN_name.py`` files) in story order; ``only`` selects by name or number."""
    found = sorted(p for p in folder.glob("[0-9][0-9]_*.py"))
    if not only:
        return found
    chosen = []
    for key in only:
        match = [
            p
            for p in found
            if p.stem == key or p.stem.split("_", 1)[0] == key.zfill(2) or p.stem.startswith(key)
        ]
        if not match:
            names = ", ".join(p.stem for p in found)
            raise NotebookError(f"no notebook matches {key!r}; notebooks are: {names}")
        chosen.extend(m for m in match if m not in chosen)
    return sorted(chosen)


def run_notebook(src: Path, out_ipynb: Path, parameters: dict[str, Any], cwd: Path | None = None) -> Any:
    """Execute one jupytext notebook with papermill, writing the executed copy to ``out_ipynb``."""
    import jupytext
    import papermill as pm

    out_ipynb.parent.mkdir(parents=True, exist_ok=True)
    nb = jupytext.read(src)
    return pm.execute_notebook(
        nb, str(out_ipynb), parameters=parameters, kernel_name="python3", language="python", progress_bar=False,
        extra_arguments=["--log-level=ERROR"],  # the kernel's own start-up chatter stays out of the run's log
        cwd=str(cwd or src.parent), log_output=False,
    )  # fmt: skip


def _move_tree(staged: Path, final: Path) -> list[str]:
    moved = []
    if not staged.exists():
        return moved
    for f in sorted(staged.rglob("*")):
        if f.is_file():
            target = final / f.relative_to(staged)
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(f, target)
            moved.append(str(target))
    return moved


def reproduce(
    data: str | os.PathLike | None = None,
    quick: bool = False,
    out: str | os.PathLike | None = None,
    jobs: int = 1,
    only: Sequence[str] | None = None,
    seed: int = 0,
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True),
    notebooks_dir: Path = paths.NOTEBOOKS_DIR,
) -> dict[str, Any]:
    """Run the notebooks and write the results summary; returns the summary (also in results/summary.json).

    Parameters
    ----------
    data : data folder, ``"synthetic"``, or None (``$GLU_DATA_DIR``, ``data/real/``, else synthetic)
    quick : small, fast runs (for tests); figures are still made
    out : root for ``figures/``, ``recordings/``, ``results/``, ``models/``, ``notebooks/``; None = the
        project's folders (:meth:`glu.paths.OutputLayout.at`)
    jobs : notebooks run at the same time (each in its own kernel)
    only : run only these notebooks (names or numbers)
    seed : the seed passed to every notebook
    log : where progress lines go (stderr by default)
    notebooks_dir : the folder of jupytext notebooks ``NN_name.py``
    """
    t_start = time.perf_counter()
    source = resolve_data(data)
    data_param = "synthetic" if source.root is None else str(source.root)
    notebooks = list_notebooks(only, notebooks_dir)
    if not notebooks:
        raise NotebookError(f"no notebooks found in {notebooks_dir}")
    if jobs < 1:
        raise NotebookError(f"-j {jobs}: the number of parallel notebooks must be at least 1")
    layout = OutputLayout.at(out)
    final = layout.published()
    executed_dir = layout.notebooks
    staging = layout.staging / uuid.uuid4().hex[:12]
    log(f"glu reproduce: {len(notebooks)} notebooks, {source.describe()}, quick={quick}, jobs={jobs}")

    results: list[NotebookResult] = []

    def one(i: int, nb: Path) -> NotebookResult:
        import papermill as pm

        name = nb.stem
        stage = staging / name
        t0 = time.perf_counter()
        out_ipynb = stage / f"{name}.ipynb"
        params = {"data": data_param, "quick": quick, "out_dir": str(stage / "out"), "seed": seed}
        try:
            run_notebook(nb, out_ipynb, params, cwd=nb.parent)
        except pm.PapermillExecutionError as e:
            kept = executed_dir / f"{name}.failed.ipynb"
            kept.parent.mkdir(parents=True, exist_ok=True)
            if out_ipynb.exists():
                os.replace(out_ipynb, kept)
            msg = f"notebook {name} failed in cell {e.cell_index} (execution count {e.exec_count}): {e.ename}: {e.evalue}"
            log(
                f"[{i}/{len(notebooks)}] {name}: FAILED after {time.perf_counter() - t0:.1f} s — {e.ename}: {e.evalue}"
            )
            return NotebookResult(name, "failed", time.perf_counter() - t0, kept, msg)
        files = []
        staged = OutputLayout.under(stage / "out")
        for kind, target in final.items():
            files += _move_tree(staged.folder(kind), target)
        executed = executed_dir / f"{name}.ipynb"
        executed.parent.mkdir(parents=True, exist_ok=True)
        os.replace(out_ipynb, executed)
        (executed_dir / f"{name}.failed.ipynb").unlink(missing_ok=True)
        dt = time.perf_counter() - t0
        log(f"[{i}/{len(notebooks)}] {name}: ok in {dt:.1f} s ({len(files)} files)")
        return NotebookResult(name, "ok", dt, executed, files=files)

    try:
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = {pool.submit(one, i, nb): nb for i, nb in enumerate(notebooks, start=1)}
            pending = set(futures)
            failed: NotebookResult | None = None
            while pending:
                done, pending = wait(pending, return_when=FIRST_EXCEPTION if jobs > 1 else "FIRST_COMPLETED")
                for f in done:
                    r = f.result()
                    results.append(r)
                    if r.status == "failed" and failed is None:
                        failed = r
                        for p in pending:
                            p.cancel()
            if failed is not None:
                raise NotebookError(
                    f"{failed.error}; executed copy kept at {failed.executed}; "
                    "outputs of earlier runs were left as they were"
                )
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        try:
            staging.parent.rmdir()
        except OSError:
            pass

    results.sort(key=lambda r: r.name)
    summary = write_summary(
        final["results"], results, source.describe(), quick, time.perf_counter() - t_start
    )
    log(
        f"glu reproduce: done in {summary['wall_time_s']:.1f} s; summary in {final['results'] / 'summary.json'}"
    )
    return summary


def write_summary(
    results_dir: Path, runs: list[NotebookResult], data: str, quick: bool, wall: float
) -> dict[str, Any]:
    """Collect every result table into ``summary.json`` and a long-format ``summary.csv``.

    A partial run (``--only``) updates the existing summary when it was made from the same data in the
    same mode: the notebooks just run replace their earlier entries, the others are kept.
    """
    import pandas as pd

    from glu.outputs import package_versions

    notebooks = {r.name: {"name": r.name, "status": r.status, "seconds": round(r.seconds, 3)} for r in runs}
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
        if "difference" in df.columns and len(df):
            diff = pd.to_numeric(df["difference"], errors="coerce").abs()
            reference = tables[name]["meta"].get("reference", "original model (BN_lab.mat)")
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
