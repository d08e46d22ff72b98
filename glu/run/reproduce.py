"""Run every notebook headless with papermill: figures, recordings, result tables, a summary and a site.

``glu reproduce`` (and ``make reproduce``) calls :func:`reproduce`. Everything is checked before anything
runs (:func:`_plan`: the numbers, the data, each notebook's parameters and manifest, and that every place of
the output layout is glu's to replace, :meth:`glu.run.publish.Store.survey`). Each notebook then runs in its
own kernel (:mod:`glu.run.execution`), writing into its own folder of a run being staged in the output
folder's store (:mod:`glu.run.publish`). A failing notebook stops the run with a message naming the notebook
and the cell and keeps its executed copy (``.glu-runs/failed/NAME.failed.ipynb``); Ctrl-C or SIGTERM stops
it at once (the kernels are killed). When every notebook succeeded, their outputs are moved into the staged
run's ``figures/``, ``results/``, ``recordings/``, ``models/`` and ``notebooks/`` (:func:`_stage`), with
``results/summary.json`` and ``summary.csv`` (every number behind every figure, the data source, the
package versions, the comparison with the original model) and the documentation site (:mod:`glu.run.site`),
and the whole run is published by one rename: the places of the layout (the project's ``results/``,
``recordings/``, ``models/``, ``build/figures/``, ``build/notebooks/``, ``build/site/``; or all under
``--out``) always show one whole run. In the project's checkout, a full run on the real data also writes its
PNG figures into the tracked ``figures/``; no other run touches a tracked file. The wall time recorded in the
summary (``wall_time_s``) covers running and staging the notebooks; the site's build time is logged after.

The executed notebooks show no path of this machine (:func:`glu.run.execution.present_executed`): their
injected parameters name the data relative to the project (or by its origin) and the published output
folder, not the staging folder the kernels wrote into.

:func:`run_one` runs a single notebook the same way (``glu run``), into a scratch folder of its own by
default.
"""

from __future__ import annotations

import math
import os
import shutil
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from glu import paths
from glu.data.source import resolve_data
from glu.errors import GluError
from glu.files import atomic_write_bytes
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
from glu.run.manifest import Manifest, ManifestError, check_outputs, read_manifest, written_outputs
from glu.run.outputs import parameters_text
from glu.run.parameters import check, non_defaults, parse_value, read_spec
from glu.run.progress import CellProgress
from glu.run.provenance import ENV as PROVENANCE_ENV
from glu.run.provenance import Provenance, read_provenance
from glu.run.publish import Store, legacy_files, reached, refuse_published
from glu.run.summary import (
    RENDERING_RECORD,
    NotebookResult,
    SummaryError,
    check_summary,
    collect_summary,
    expected_seconds,
    previous_summary,
    save_summary,
    write_rendering_record,
)

WORK = "_work"
"""In a staging run folder: each notebook's own folder while it runs (``_work/NAME/out``)."""


class NotebookError(GluError):
    """A notebook failed while running, or a notebook name matches none."""


class NotebookFailed(NotebookError):
    """A notebook's cell raised: the run failed (exit status 1, not the 2 of bad input)."""

    exit_status = 1


def list_notebooks(only: Sequence[str] | None = None, folder: Path = paths.NOTEBOOKS_DIR) -> list[Path]:
    """The notebooks (jupytext ``NN_name.py`` files) in story order; ``only`` selects by name or number."""
    found = sorted(folder.glob("[0-9][0-9]_*.py"))
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


def _move_tree(staged: Path, final: Path) -> list[str]:
    moved = []
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
        """Report a notebook's end: ``[k/n]`` counts the notebooks finished so far (in the order they end)."""
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


@dataclass
class _Plan:
    """What a run is about to do, checked before anything runs."""

    source: Any
    quick: bool
    seed: int
    jobs: int
    notebooks: list[Path]
    layout: OutputLayout
    store: Store
    manifests: dict[str, Manifest] = field(default_factory=dict)
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    non_default: dict[str, dict[str, Any]] = field(default_factory=dict)
    kept: dict[str, str] = field(default_factory=dict)
    made: Provenance | None = None


def reproduce(
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
    force: bool = False,
) -> dict[str, Any]:
    """Run the notebooks and publish the whole run if all succeed; returns the summary (also in results/).

    The run holds the lock of the output folder (:func:`glu.run.lock.run_lock`): a second run on the same
    project or ``--out`` folder is refused in one line naming the first's process id. The glu that runs (its
    version and commit, :mod:`glu.run.provenance`) is read once, before any notebook, and every output of
    the run names it.

    Parameters
    ----------
    data : data folder, ``"synthetic"``, or None (``$GLU_DATA_DIR``, the fetched data, else synthetic)
    quick : small, fast runs (for tests): each notebook with the quick preset of its manifest
        (:mod:`glu.run.manifest`); every figure is still made
    out : root for ``figures/``, ``recordings/``, ``results/``, ``models/``, ``notebooks/``, ``site/``;
        None = the project's places (:meth:`glu.paths.OutputLayout.at`)
    jobs : notebooks run at the same time (each in its own kernel)
    only : run only these notebooks (names or numbers); the published run keeps the others' outputs
    seed : the seed passed to every notebook
    log : where progress lines go (stderr by default)
    notebooks_dir : the folder of jupytext notebooks ``NN_name.py``
    progress : live progress bar; None = when stderr is a terminal
    site : also build the documentation site of the run (:func:`glu.run.site.build_site`)
    force : leave a place of the output layout that holds what glu did not write untouched (the run is
        then published in the store only) instead of refusing

    Raises
    ------
    NotebookError : a notebook failed (nothing published); :class:`glu.run.publish.PublishError` : a place
    holds what glu did not write (nothing ran); KeyboardInterrupt : interrupted (nothing published, kernels
    killed, staging removed); :class:`glu.run.site.SiteError` : the run was published without its site
    """
    with run_lock(OutputLayout.at(out).root), _made_by(read_provenance()) as made:
        t_start = time.perf_counter()
        plan = _plan(data, quick, out, jobs, only, seed, notebooks_dir, force)
        plan.made = made
        run = plan.store.begin()
        try:
            where = f"{plan.source.location()}, quick={quick}, jobs={jobs}"
            log(f"glu reproduce: {len(plan.notebooks)} notebooks, {where}")
            results = _run_all(plan, run, log, progress)
            summary = _stage(plan, run, results)
            summary["wall_time_s"] = round(time.perf_counter() - t_start, 3)
            save_summary(run / "results", summary)
            site_error = _build_site(plan, run, summary, log, notebooks_dir) if site else None
            reached("site")
            plan.store.record(run, _record(plan, run, results))
            plan.store.publish(run, log)
        finally:
            plan.store.discard(run)
        _promote_figures(plan, run, log)
        log(
            f"glu reproduce: done in {summary['wall_time_s']:.1f} s; summary in "
            f"{plan.layout.results / 'summary.json'}"
        )
        if site_error is not None:
            raise site_error
        return summary


@contextmanager
def _made_by(made: Provenance) -> Iterator[Provenance]:
    """Hand the run's provenance to the notebooks' kernels (:data:`glu.run.provenance.ENV`) while it runs."""
    before = os.environ.get(PROVENANCE_ENV)
    os.environ[PROVENANCE_ENV] = before or made.label()  # a caller's pinned line wins (a re-render)
    try:
        yield made
    finally:
        if before is None:
            os.environ.pop(PROVENANCE_ENV, None)
        else:
            os.environ[PROVENANCE_ENV] = before


def _plan(
    data: str | os.PathLike | None,
    quick: bool,
    out: str | os.PathLike | None,
    jobs: int,
    only: Sequence[str] | None,
    seed: int,
    notebooks_dir: Path,
    force: bool,
) -> _Plan:
    """Check everything a run needs before anything runs: the numbers, the data, every notebook's
    parameters and manifest, and the output layout's places (:meth:`glu.run.publish.Store.survey`)."""
    if not 1 <= jobs <= 64:
        raise NotebookError(f"-j {jobs}: the number of notebooks run at once must be between 1 and 64")
    if not 0 <= seed < 2**32:
        raise NotebookError(f"--seed {seed}: a seed must be between 0 and 2**32 - 1")
    source = resolve_data(data)
    notebooks = list_notebooks(only, notebooks_dir)
    if not notebooks:
        raise NotebookError(f"no notebooks found in {notebooks_dir}")
    layout = OutputLayout.at(out)
    plan = _Plan(source, quick, seed, jobs, notebooks, layout, Store(layout, force=force))
    for nb in notebooks:  # every notebook takes these parameters: refuse before anything runs
        plan.manifests[nb.stem] = manifest = read_manifest(nb)
        spec = read_spec(nb)
        missing = {"data", "out_dir", "seed"} - set(spec)
        if missing:
            raise NotebookError(f"{nb.stem}: its parameters cell lacks {', '.join(sorted(missing))}")
        plan.params[nb.stem] = {**(manifest.quick if quick else {}), "seed": seed}
        plan.non_default[nb.stem] = non_defaults(spec, check(spec, plan.params[nb.stem], nb.stem))
    manifests = {nb.stem: read_manifest(nb) for nb in list_notebooks(None, notebooks_dir)}
    plan.store.survey(legacy_files(layout, manifests) if layout.tracked_figures is not None else None)
    return plan


def _run_all(
    plan: _Plan, run: Path, log: Callable[[str], None], progress: bool | None
) -> list[NotebookResult]:
    """Run every notebook of the plan, each staging into ``run/_work/NAME/``; the results when all
    succeeded, else :class:`NotebookFailed` (the others stopped)."""
    shown = {  # what the executed notebooks show of the data and the output folder (no machine path)
        "data": _shown_data(plan.source),
        "out_dir": (shown_path(plan.layout.root), "published to figures/, results/, recordings/, models/"),
    }
    live = sys.stderr.isatty() if progress is None else progress
    bar = _Progress(plan.notebooks, log, live)
    results: list[NotebookResult] = []
    pool = ThreadPoolExecutor(max_workers=plan.jobs)
    futures: set[Future] = set()
    failed: NotebookResult | None = None
    try:
        threads = max(1, available_cores() // plan.jobs)  # each kernel's share of the cores for BLAS/OpenMP
        expected = expected_seconds(plan.layout, plan.notebooks, plan.quick)
        for _, nb in run_order(plan.notebooks, plan.jobs, expected):
            handle = bar.handle(nb.stem)
            handle.threads = threads
            futures.add(pool.submit(_run_notebook, plan, nb, run / WORK / nb.stem, handle, bar, shown))
        pending = set(futures)
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
                    _stop_all(pending, bar)
    except BaseException:
        _stop_all(futures, bar)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        bar.close()
    if failed is not None:
        raise NotebookFailed(
            f"{failed.error}; executed copy kept at {failed.executed}; nothing was published: "
            "the outputs of earlier runs are as they were"
        )
    return sorted(results, key=lambda r: r.name)


def _run_notebook(
    plan: _Plan, nb: Path, work: Path, handle: RunHandle, bar: _Progress, shown: dict[str, tuple[Any, str]]
) -> NotebookResult:
    """Run one notebook into ``work`` (its outputs in ``work/out``) and check them against its manifest."""
    pm = load_papermill()
    name = nb.stem
    t0 = time.perf_counter()
    out_ipynb = work / f"{name}.ipynb"
    params = {**plan.params[name], "data": _data_param(plan.source), "out_dir": str(work / "out")}

    def failed(msg: str, why: str) -> NotebookResult:
        kept = plan.store.failed / f"{name}.failed.ipynb"
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
            f"notebook {name} failed in cell {e.cell_index} (execution count {e.exec_count}): "
            f"{e.ename}: {e.evalue}",
            f"{e.ename}: {e.evalue}",
        )
    dt = time.perf_counter() - t0
    try:
        check_outputs(plan.manifests[name], written_outputs(work / "out"), plan.source.is_real)
    except ManifestError as e:
        return failed(f"notebook {name} ran, but {e}", str(e))
    executed = plan.layout.notebooks / f"{name}.ipynb"
    present_executed(out_ipynb, shown, shown_path(nb), shown_path(executed))
    bar.finished(name, f"{name}: ok in {dt:.1f} s")
    return NotebookResult(name, "ok", dt, out_ipynb, parameters=plan.non_default[name])


def _stage(plan: _Plan, run: Path, results: list[NotebookResult]) -> dict[str, Any]:
    """Move every notebook's outputs from its work folder into the run's folders, keep the published
    run's outputs of the notebooks not run (a partial run on the same data in the same mode), and return
    the run's summary (its ``wall_time_s`` not yet set)."""
    staged = OutputLayout.under(run)
    current = plan.store.current()
    previous = previous_summary(current / "results") if current is not None else {}
    try:  # a malformed summary (edited, or damaged) is kept no more than a missing one
        check_summary(previous)
        same = previous.get("data_source") == plan.source.describe() and previous.get("quick") == plan.quick
    except SummaryError:
        same = False
    ran = {r.name for r in results}
    others = [nb["name"] for nb in previous.get("notebooks", []) if same and nb.get("name") not in ran]
    plan.kept = plan.store.carry_over(run, others)
    for kind in (*staged.published(), "notebooks"):  # every place of the run resolves, even empty
        staged.folder(kind).mkdir(parents=True, exist_ok=True)
    for r in results:
        out = OutputLayout.under(run / WORK / r.name / "out")
        for kind, target in staged.published().items():
            r.files += _move_tree(out.folder(kind), target)
        os.replace(r.executed, staged.notebooks / f"{r.name}.ipynb")
        r.executed = plan.layout.notebooks / f"{r.name}.ipynb"
        (plan.store.failed / f"{r.name}.failed.ipynb").unlink(missing_ok=True)
    shutil.rmtree(run / WORK, ignore_errors=True)
    summary = collect_summary(
        staged.results, results, plan.source.describe(), plan.quick, previous=previous if same else {}
    )
    label = os.environ.get(PROVENANCE_ENV) or plan.made.label()
    summary.update(made_by=label, provenance=plan.made.as_dict())
    write_rendering_record(staged.figures, plan.source.describe(), plan.quick, label)
    reached("staged")
    return summary


def _record(plan: _Plan, run: Path, results: list[NotebookResult]) -> dict[str, str]:
    """Each notebook's files in the run folder (relative path → notebook), for a later partial run: those
    kept from the published run, and those of the notebooks run."""
    record = dict(plan.kept)
    for r in results:
        for f in r.files:
            record[Path(f).relative_to(run).as_posix()] = r.name
        record[f"notebooks/{r.name}.ipynb"] = r.name
    return record


def _build_site(
    plan: _Plan, run: Path, summary: dict[str, Any], log: Callable[[str], None], notebooks_dir: Path
) -> GluError | None:
    """Build the run's site into ``run/site``; the error when it could not be built (the run is then
    published without a site, and the error raised once it is)."""
    from glu.run.site import SiteError, build_site

    try:
        build_site(
            OutputLayout.under(run),
            summary,
            log=log,
            notebooks_dir=notebooks_dir,
            work=plan.store.site_work,
            published=plan.layout,
        )
    except SiteError as e:
        return SiteError(f"{e}\nthe run was published without its site (`make docs` builds it again)")
    return None


def _promote_figures(plan: _Plan, run: Path, log: Callable[[str], None]) -> None:
    """In the project's checkout, after a full run on the real data with the default seed: its PNG figures
    and their rendering record into the tracked ``figures/`` (never from synthetic data or a quick run)."""
    tracked = plan.layout.tracked_figures
    if tracked is None or not plan.source.is_real or plan.quick or plan.seed != 0:
        return
    figures = run / "figures"
    files = sorted(figures.glob("*.png")) + [figures / RENDERING_RECORD]
    changed = 0
    for f in files:
        target = tracked / f.name
        data = f.read_bytes()
        if not target.is_file() or target.read_bytes() != data:
            atomic_write_bytes(target, data)
            changed += 1
    log(f"glu reproduce: {changed} of the tracked figures in figures/ rewritten from the real data")


def _data_param(source: Any) -> str:
    """The data as a kernel is given it: ``synthetic``, or its folder."""
    return "synthetic" if source.root is None else str(source.root)


def _shown_data(source: Any) -> tuple[str, str]:
    """The data as an executed notebook shows it: ``synthetic``, or its folder relative to the project
    (:func:`shown_path`), with what it is (:meth:`glu.data.DataSource.describe`: its public origin)."""
    return ("synthetic" if source.root is None else shown_path(source.root), source.describe())


def _stop_all(pending: set[Future], bar: _Progress) -> None:
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
    if out is not None:
        layout = OutputLayout.at(out)
        refuse_published(layout, "glu run")
    else:
        layout = OutputLayout.scratch(src.stem)
    params = {**parsed, "data": _data_param(source), "out_dir": str(layout.root)}
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
