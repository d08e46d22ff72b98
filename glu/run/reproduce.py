"""Run every notebook headless with papermill: figures, recordings, result tables, a summary and a site.

``glu reproduce`` (and ``make reproduce``) calls :func:`reproduce`. Each notebook runs in its own kernel
(:mod:`glu.run.execution`), writing into a private staging folder. The run is all-or-nothing: only when every
notebook succeeded are the staged files moved into the folders of the output layout
(:class:`glu.paths.OutputLayout`: ``figures/``, ``recordings/``, ``results/``, ``models/``, the executed
notebooks into ``build/notebooks/``; or all under ``--out``), so figures, recordings, models and
``results/summary.json`` always belong to one run. A failing notebook stops the run with a message naming
the notebook and the cell and keeps its executed copy (``NAME.failed.ipynb``); Ctrl-C or SIGTERM stops
it at once (the kernels are killed). Either way nothing is published and the staging folder is removed;
a staging folder left by a killed process is removed by the next run. At the end
``results/summary.json`` and ``results/summary.csv`` collect every number behind every figure, the data
source, the package versions and the comparison with the original model, and ``site/`` (by default
``build/site/``) gets the documentation site of the run (:mod:`glu.run.site`: the executed notebooks, the
docs pages, the API reference). The wall time recorded in the summary (``wall_time_s``) covers running
and publishing the notebooks; the site's build time is logged after it.

The executed notebooks show no path of this machine (:func:`glu.run.execution.present_executed`): their
injected parameters name the data relative to the project (or by its origin) and the published output
folder, not the staging folder the kernels wrote into.

:func:`run_one` runs a single notebook the same way (``glu run``), into its scratch folder by default.
"""

from __future__ import annotations

import math
import os
import shutil
import sys
import time
import uuid
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from glu import paths
from glu.data.source import resolve_data
from glu.errors import GluError
from glu.machine import available_cores
from glu.paths import OutputLayout
from glu.run.execution import (
    NotebookStopped,
    RunHandle,
    load_papermill,
    present_executed,
    run_notebook,
    shown_path,
)
from glu.run.lock import run_lock
from glu.run.manifest import ManifestError, check_outputs, read_manifest, written_outputs
from glu.run.outputs import parameters_text
from glu.run.parameters import check, non_defaults, parse_value, read_spec
from glu.run.progress import CellProgress
from glu.run.provenance import ENV as PROVENANCE_ENV
from glu.run.provenance import Provenance, read_provenance
from glu.run.summary import (
    NotebookResult,
    collect_summary,
    expected_seconds,
    save_summary,
    summary_csv,
    write_rendering_record,
)

OWNER_FILE = "owner.pid"
"""In each staging folder: the process id of the run that owns it."""


class NotebookError(GluError):
    """A notebook failed while running, or a notebook name matches none."""


class NotebookFailed(NotebookError):
    """A notebook's cell raised: the run failed (exit status 1, not the 2 of bad input)."""

    exit_status = 1


def list_notebooks(only: Sequence[str] | None = None, folder: Path = paths.NOTEBOOKS_DIR) -> list[Path]:
    """The notebooks (jupytext ``NN_name.py`` files) in story order; ``only`` selects by name or number."""
    found = sorted(p for p in folder.glob("[0-9][0-9]_*.py"))
    if only is None:
        return found
    chosen = []
    for key in only:
        key = str(key).strip()
        if key.isdigit():  # a number names one notebook: "8" and "08" are 08_…, "0" and "1" are not prefixes
            match = [p for p in found if int(p.stem.split("_", 1)[0]) == int(key)]
        else:
            match = [p for p in found if key and (p.stem == key or p.stem.startswith(key))]
        if not match:
            names = ", ".join(p.stem for p in found)
            raise NotebookError(f"no notebook matches {key!r}; notebooks are: {names}")
        chosen.extend(m for m in match if m not in chosen)
    return sorted(chosen)


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def clean_stale_staging(staging_root: Path) -> list[Path]:
    """Remove staging folders whose owning process is gone (a run killed with SIGKILL); return them."""
    removed = []
    if not staging_root.is_dir():
        return removed
    for d in staging_root.iterdir():
        owner = d / OWNER_FILE
        try:
            pid = int(owner.read_text().strip())
        except (OSError, ValueError):
            pid = None
        if pid is None or not _pid_alive(pid):
            shutil.rmtree(d, ignore_errors=True)
            removed.append(d)
    return removed


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


class _Progress:
    """Live progress on a terminal (tqdm, over all cells); plain lines when stderr is not a TTY."""

    def __init__(self, notebooks: Sequence[Path], log: Callable[[str], None], live: bool):
        self.log = log
        self.running: dict[str, RunHandle] = {}
        self.started: dict[str, float] = {}
        self.done = 0
        self.n = len(notebooks)
        self.bar = None
        if live:
            from tqdm import tqdm

            self.bar = tqdm(total=self.n, unit="notebook", file=sys.stderr, leave=False, dynamic_ncols=True)

    def handle(self, name: str) -> RunHandle:
        h = RunHandle()
        self.running[name] = h
        self.started[name] = time.perf_counter()
        return h

    def finished(self, name: str, line: str) -> None:
        """Report one notebook done: ``line`` after ``[k/n]``, k counting the notebooks finished (they
        finish in any order, so k only goes up)."""
        self.running.pop(name, None)
        self.done += 1
        line = f"[{self.done}/{self.n}] {line}"
        if self.bar is not None:
            self.bar.write(line, file=sys.stderr)
            self.bar.update(1)
        else:
            self.log(line)

    def tick(self) -> None:
        if self.bar is None:
            return
        now = time.perf_counter()
        parts = [
            f"{n} cell {h.cell + 1}/{h.n_cells} {now - self.started[n]:.0f}s"
            if h.n_cells
            else f"{n} starting"
            for n, h in self.running.items()
        ]
        self.bar.set_postfix_str(" · ".join(parts), refresh=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run_order(notebooks: Sequence[Path], jobs: int, expected: Mapping[str, float]) -> list[tuple[int, Path]]:
    """(story number, notebook) in the order they start: story order with one job; with several, the
    longest first by ``expected`` seconds (:func:`glu.run.summary.expected_seconds`: the last run's times,
    else on a first run the time each notebook declares in its header), so that the last to finish is a
    short one. A notebook with no expected time starts before all others, the later ones in the story
    first. The order changes no output: each notebook runs alone in its kernel, and publishing is by name.

    >>> nbs = [Path("01_a.py"), Path("02_b.py"), Path("03_c.py"), Path("04_d.py")]
    >>> [p.stem for _, p in run_order(nbs, 2, {"01_a": 3.0, "02_b": 10.0, "03_c": 3.0, "04_d": 30.0})]
    ['04_d', '02_b', '03_c', '01_a']
    >>> [i for i, _ in run_order(nbs, 2, {"01_a": 3.0, "02_b": 10.0})]
    [4, 3, 2, 1]
    >>> [i for i, _ in run_order(nbs, 1, {"04_d": 30.0})]
    [1, 2, 3, 4]
    """
    numbered = list(enumerate(notebooks, start=1))
    if jobs == 1:
        return numbered
    return sorted(numbered, key=lambda item: (-expected.get(item[1].stem, math.inf), -item[0]))


def reproduce(
    data: str | os.PathLike | None = None,
    quick: bool = False,
    out: str | os.PathLike | None = None,
    **kwargs: Any,
) -> dict[str, Any]:
    """:func:`_reproduce` holding the lock of the output folder (:func:`glu.run.lock.run_lock`): a second
    run on the same project or ``--out`` folder is refused in one line naming the first's process id. The
    glu that runs (its version and commit, :mod:`glu.run.provenance`) is read once, before any notebook,
    and every output of the run names it."""
    if out is None:
        out = default_out(resolve_data(data), quick)
    with run_lock(OutputLayout.at(out).root), _made_by(read_provenance()) as made:
        return _reproduce(data, quick, out, made=made, **kwargs)


def default_out(source: Any, quick: bool) -> Path | None:
    """Where a run without ``--out`` publishes: the project's own folders (None) only for a full run on
    the real data, whose figures are the ones tracked in git; a run on synthetic data, or a quick one,
    writes under ``build/synthetic/`` or ``build/quick/`` instead (the same layout: ``figures/``, …,
    ``site/``), so that it never overwrites a published figure. None too when glu is installed (then
    :meth:`glu.paths.OutputLayout.project` asks for ``-o DIR``)."""
    if paths.PROJECT_ROOT is None or (source.is_real and not quick):
        return None
    return paths.PROJECT_ROOT / "build" / ("quick" if quick else "synthetic")


@contextmanager
def _made_by(made: Provenance) -> Iterator[Provenance]:
    """Hand the run's provenance to the notebooks' kernels (:data:`glu.run.provenance.ENV`) while it runs."""
    before = os.environ.get(PROVENANCE_ENV)
    os.environ[PROVENANCE_ENV] = made.label()
    try:
        yield made
    finally:
        if before is None:
            os.environ.pop(PROVENANCE_ENV, None)
        else:
            os.environ[PROVENANCE_ENV] = before


def _reproduce(
    data: str | os.PathLike | None = None,
    quick: bool = False,
    out: str | os.PathLike | None = None,
    jobs: int = 1,
    only: Sequence[str] | None = None,
    seed: int = 0,
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True),
    notebooks_dir: Path = paths.NOTEBOOKS_DIR,
    progress: bool | None = None,
    site: bool = True,
    made: Provenance | None = None,
) -> dict[str, Any]:
    """Run the notebooks and publish their outputs if all succeed; returns the summary (also in results/).

    Parameters
    ----------
    data : data folder, ``"synthetic"``, or None (``$GLU_DATA_DIR``, the fetched data, else synthetic)
    quick : small, fast runs (for tests): each notebook with the quick preset of its manifest
        (:mod:`glu.run.manifest`); every figure is still made
    out : root for ``figures/``, ``recordings/``, ``results/``, ``models/``, ``notebooks/``, ``site/``;
        None = the project's folders (:meth:`glu.paths.OutputLayout.at`; :func:`reproduce` gives
        :func:`default_out` instead)
    jobs : notebooks run at the same time (each in its own kernel)
    only : run only these notebooks (names or numbers)
    seed : the seed passed to every notebook
    log : where progress lines go (stderr by default)
    notebooks_dir : the folder of jupytext notebooks ``NN_name.py``
    progress : live progress bar; None = when stderr is a terminal
    site : also build the documentation site of the run (:func:`glu.run.site.build_site`)
    made : the glu that runs (:func:`glu.run.provenance.read_provenance`, read by :func:`reproduce`)

    Raises
    ------
    NotebookError : a notebook failed (nothing published); KeyboardInterrupt : interrupted (nothing
    published, kernels killed, staging removed); :class:`glu.run.site.SiteError` : the notebooks' outputs
    were published but the site could not be built (the previous site is kept)
    """
    t_start = time.perf_counter()
    if not 1 <= jobs <= 64:
        raise NotebookError(f"-j {jobs}: the number of notebooks run at once must be between 1 and 64")
    if not 0 <= seed < 2**32:
        raise NotebookError(f"--seed {seed}: a seed must be between 0 and 2**32 - 1")
    source = resolve_data(data)
    data_param = "synthetic" if source.root is None else str(source.root)
    notebooks = list_notebooks(only, notebooks_dir)
    if not notebooks:
        raise NotebookError(f"no notebooks found in {notebooks_dir}")
    manifests, run_params, non_default = {}, {}, {}
    for nb in notebooks:  # every notebook takes these parameters: refuse before anything runs
        manifests[nb.stem] = manifest = read_manifest(nb)
        spec = read_spec(nb)
        missing = {"data", "out_dir", "seed"} - set(spec)
        if missing:
            raise NotebookError(f"{nb.stem}: its parameters cell lacks {', '.join(sorted(missing))}")
        run_params[nb.stem] = {**(manifest.quick if quick else {}), "seed": seed}
        non_default[nb.stem] = non_defaults(spec, check(spec, run_params[nb.stem], nb.stem))
    layout = OutputLayout.at(out)
    shown = {  # what the executed notebooks show of the data and the output folder (no machine path)
        "data": _shown_data(source),
        "out_dir": (shown_path(layout.root), "published to figures/, results/, recordings/, models/ there"),
    }
    final = layout.published()
    executed_dir = layout.notebooks
    clean_stale_staging(layout.staging)
    staging = layout.staging / uuid.uuid4().hex[:12]
    staging.mkdir(parents=True)
    (staging / OWNER_FILE).write_text(str(os.getpid()))
    log(f"glu reproduce: {len(notebooks)} notebooks, {source.location()}, quick={quick}, jobs={jobs}")
    live = sys.stderr.isatty() if progress is None else progress
    bar = _Progress(notebooks, log, live)

    def one(nb: Path, handle: RunHandle) -> NotebookResult:
        pm = load_papermill()
        name = nb.stem
        stage = staging / name
        t0 = time.perf_counter()
        out_ipynb = stage / f"{name}.ipynb"
        params = {**run_params[name], "data": data_param, "out_dir": str(stage / "out")}

        def failed(msg: str, why: str) -> NotebookResult:
            kept = executed_dir / f"{name}.failed.ipynb"
            kept.parent.mkdir(parents=True, exist_ok=True)
            if out_ipynb.exists():
                os.replace(out_ipynb, kept)
            dt = time.perf_counter() - t0
            bar.finished(name, f"{name}: FAILED after {dt:.1f} s — {why}")
            return NotebookResult(name, "failed", dt, kept, msg)

        try:
            run_notebook(nb, out_ipynb, params, cwd=nb.parent, handle=handle)
        except pm.PapermillExecutionError as e:
            return failed(
                (
                    f"notebook {name} failed in cell {e.cell_index} (execution count {e.exec_count}): "
                    f"{e.ename}: {e.evalue}"
                ),
                f"{e.ename}: {e.evalue}",
            )
        dt = time.perf_counter() - t0
        try:
            check_outputs(manifests[name], written_outputs(stage / "out"), source.is_real)
        except ManifestError as e:
            return failed(f"notebook {name} ran, but {e}", str(e))
        present_executed(out_ipynb, shown, shown_path(nb), shown_path(executed_dir / f"{name}.ipynb"))
        bar.finished(name, f"{name}: ok in {dt:.1f} s")
        return NotebookResult(name, "ok", dt, out_ipynb, parameters=non_default[name])

    results: list[NotebookResult] = []
    try:
        pool = ThreadPoolExecutor(max_workers=jobs)
        futures: dict[Future, str] = {}
        try:
            threads = max(1, available_cores() // jobs)  # each kernel's share of the cores for BLAS/OpenMP
            for _, nb in run_order(notebooks, jobs, expected_seconds(layout, notebooks, quick)):
                handle = bar.handle(nb.stem)
                handle.threads = threads
                futures[pool.submit(one, nb, handle)] = nb.stem
            pending = set(futures)
            failed: NotebookResult | None = None
            while pending:
                done, pending = wait(pending, timeout=0.25, return_when=FIRST_COMPLETED)
                bar.tick()
                for f in done:
                    if f.cancelled():  # not started: cancelled when another notebook failed
                        continue
                    try:
                        r = f.result()
                    except NotebookStopped:
                        continue
                    results.append(r)
                    if r.status == "failed" and failed is None:
                        failed = r
                        _stop_all(pending, futures, bar)
        except BaseException:
            _stop_all(set(futures), futures, bar)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
            bar.close()
        if failed is not None:
            raise NotebookFailed(
                f"{failed.error}; executed copy kept at {failed.executed}; nothing was published: "
                "the outputs of earlier runs are as they were"
            )
        for r in sorted(results, key=lambda r: r.name):  # every notebook succeeded: publish them all
            staged = OutputLayout.under(staging / r.name / "out")
            for kind, target in final.items():
                r.files += _move_tree(staged.folder(kind), target)
            executed = executed_dir / f"{r.name}.ipynb"
            executed.parent.mkdir(parents=True, exist_ok=True)
            os.replace(r.executed, executed)
            r.executed = executed
            (executed_dir / f"{r.name}.failed.ipynb").unlink(missing_ok=True)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        try:
            staging.parent.rmdir()
        except OSError:
            pass

    results.sort(key=lambda r: r.name)
    made = made or read_provenance()
    summary = collect_summary(final["results"], results, source.describe(), quick)
    summary.update(made_by=made.label(), provenance=made.as_dict())
    csv = summary_csv(summary)
    write_rendering_record(final["figures"], source.describe(), quick, made.label())
    summary["wall_time_s"] = round(time.perf_counter() - t_start, 3)
    summary_file = save_summary(final["results"], summary, csv)
    log(f"glu reproduce: done in {summary['wall_time_s']:.1f} s; summary in {summary_file}")
    if site:
        from glu.run.site import build_site

        build_site(layout, summary, log=log, notebooks_dir=notebooks_dir)
    return summary


def _shown_data(source: Any) -> tuple[str, str]:
    """The data as an executed notebook shows it: ``synthetic``, or its folder relative to the project
    (:func:`shown_path`), with what it is (:meth:`glu.data.DataSource.describe`: its public origin)."""
    return ("synthetic" if source.root is None else shown_path(source.root), source.describe())


def _stop_all(pending: set[Future], futures: Mapping[Future, str], bar: _Progress) -> None:
    """Cancel what has not started, and kill the kernels of what is running."""
    for f in pending:
        f.cancel()
    for h in list(bar.running.values()):
        h.stop()


def run_one(
    notebook: str,
    values: Mapping[str, str],
    data: str | os.PathLike | None = None,
    out: str | os.PathLike | None = None,
    notebooks_dir: Path = paths.NOTEBOOKS_DIR,
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True),
    quick: bool = False,
    progress: bool = True,
) -> tuple[Path, OutputLayout]:
    """Run one notebook headless (``glu run``): check the parameters first, then execute.

    Returns the executed notebook and the layout its outputs went to. Raises
    :class:`glu.errors.ParameterError` (nothing executed) for an unknown name, a wrong type or a value out
    of range, :class:`NotebookError` when a cell fails.

    Parameters
    ----------
    notebook : the notebook's name or number
    values : parameter name → its text on the command line (``-p NAME VALUE``), parsed by its type
    data, out : the data source and the output root (default: the notebook's scratch folder)
    quick : start from the quick preset of the notebook's manifest (``values`` win over it)
    progress : report each code cell as it starts, on stderr (:class:`glu.run.progress.CellProgress`: a
        bar on a terminal, one line per cell otherwise)
    """
    pm = load_papermill()
    (src,) = list_notebooks([notebook], notebooks_dir)[:1]
    spec = read_spec(src)
    for plumbing in ("data", "out_dir"):
        if plumbing in values:
            flag = "--data" if plumbing == "data" else "-o/--out"
            raise NotebookError(f"{src.stem}: give {plumbing!r} with {flag}, not -p")
    parsed = {name: parse_value(spec[name], text, src.stem) for name, text in values.items() if name in spec}
    if quick:
        parsed = {**read_manifest(src).quick, **parsed}
    unknown = {name: text for name, text in values.items() if name not in spec}
    check(spec, {**parsed, **unknown}, src.stem)  # refuses unknown names, with a suggestion
    source = resolve_data(data)
    layout = OutputLayout.at(out) if out is not None else OutputLayout.scratch(src.stem)
    params = {
        **parsed,
        "data": "synthetic" if source.root is None else str(source.root),
        "out_dir": str(layout.root),
    }
    executed = layout.notebooks / f"{src.stem}.ipynb"
    label = parameters_text(parsed) or "default parameters"
    log(f"glu run: {src.stem} with {label}, {source.location()} …")
    try:
        if progress:
            with CellProgress(src.stem) as cells:
                run_notebook(src, executed, params, cwd=src.parent, handle=cells.handle)
        else:
            run_notebook(src, executed, params, cwd=src.parent)
    except pm.PapermillExecutionError as e:
        raise NotebookFailed(
            f"notebook {src.stem} failed in cell {e.cell_index}: {e.ename}: {e.evalue}; "
            f"executed copy at {executed}"
        ) from None
    shown = {"data": _shown_data(source), "out_dir": (shown_path(layout.root), "")}
    present_executed(executed, shown, shown_path(src), shown_path(executed))
    return executed, layout
