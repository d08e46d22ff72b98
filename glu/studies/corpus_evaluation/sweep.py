"""Run a corpus sweep as Dask tasks, resumably, and merge the chunks into tables.

The grid of a sweep is action prior × noise × viewpoint (the simulated conditions) × recogniser seed ×
inference network × p_HMM reading (the readings) × strategy × observed fraction. One **task** is one chunk
of episodes of one condition, for every recogniser seed: it simulates each seed's episodes once and scores
them at every fraction with every strategy under every reading, since those share the gesture and its
forward pass (:meth:`glu.studies.corpus_evaluation.evaluation.Evaluator.run_chunk`); the seeds' two-level
bootstrap sums add up (:mod:`glu.studies.corpus_evaluation.intervals`), so a task stores one sum per reading.
Tasks run

* on a ``LocalCluster`` sized to the machine (one single-threaded worker process per core) by default;
* on an existing cluster with ``scheduler="tcp://host:8786"`` (``dask scheduler`` and ``dask worker``,
  see ``docs/sweeps.md``); the workers need glu installed;
* in this process, one after another, with ``scheduler="synchronous"`` (tests, notebooks, debugging).

Each finished chunk is written by this process (workers need no shared disk) to ``OUT/chunks/`` through
a temporary file and a rename, so an interrupted sweep leaves only whole chunks; running it again computes
only the missing ones. A chunk's numbers depend only on the settings, the seed and its index, and chunks
are merged in index order, so the same settings give the same tables on any cluster.

The output folder::

    OUT/sweep.json          the settings, the data source and a fingerprint of everything behind the numbers
    OUT/recognizers/seed-NNN-FEATURES.json   the gesture HMMs of each recogniser seed and feature set
                            (trained once, reused on resume)
    OUT/chunks/*.npz        the summed statistics of each chunk (estimate, bootstrap replicates, and each
                            seed's own estimate)
    OUT/results.parquet     THE table: every metric with its 95 % two-level interval, per cell of the design
                            (effects, action prior, inference network, p_HMM reading, feature set), noise
                            and viewpoint, pooled over the viewpoints (viewpoint "all"), over the noise
                            levels (noise NaN), and both
    OUT/differences.parquet paired differences between strategies, with intervals, bootstrap p-values and
                            verdicts, unadjusted and adjusted (Benjamini–Hochberg) within each family: per
                            viewpoint, per noise level, and pooled
    OUT/reliability.parquet reliability diagrams of p_HMM (target action, strategy gesture) and of every
                            strategy's action and effect
    OUT/seeds.parquet       each recogniser seed's own estimates (pooled over noise and viewpoints)
    OUT/calibration.parquet the calibrated readings' β per seed, feature set and observed fraction, whether
                            it sits at a bound, and the recogniser's accuracy on the gestures it was fitted on
    OUT/summary.json, OUT/summary.csv   the tidy summary: the overall metrics at the full gesture, and
                            which strategy wins each cell of the design

The tables and the summary are one set: ``summary.json`` is removed before the tables are (re)written and
written last (:func:`glu.files.marked_set`), and a folder without it is not a finished sweep
(:func:`~glu.studies.corpus_evaluation.tables.read_tables` refuses it), so a merge cut short never leaves new
tables beside old ones.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from glu import __version__
from glu.errors import DataError, GluError
from glu.files import atomic_path, atomic_write_json, marked_set
from glu.machine import SYNCHRONOUS, available_cores, check_reachable, check_scheduler, dask_client
from glu.saved import made_with
from glu.studies.corpus_evaluation import robots
from glu.studies.corpus_evaluation.config import SweepConfig
from glu.studies.corpus_evaluation.evaluation import Evaluator
from glu.studies.corpus_evaluation.tables import TABLES, chunk_path, merge, write_chunk
from glu.studies.episodes import Condition

FORMAT = "glu-sweep"
FORMAT_VERSION = 3


@dataclass
class SweepResult:
    """What a sweep produced: the folder, its tables, and how much was computed now."""

    out: Path
    metrics: pd.DataFrame
    differences: pd.DataFrame
    reliability: pd.DataFrame
    seeds: pd.DataFrame
    summary: dict[str, Any]
    computed: int
    reused: int
    seconds: float
    task_cpu_seconds: float = 0.0
    """CPU time the tasks computed now took, summed over workers (the parallel part of ``seconds``)."""


# ------------------------------------------------------------------------------------------ preparing
def _experiments(config: SweepConfig) -> tuple[pd.DataFrame, str]:
    from glu.data import load_experiments, resolve_data

    net = config.network
    source = resolve_data(net.data)
    table = load_experiments(source, net.words)
    label = (
        f"{source.describe()}: network learned from {len(table)} experiments (words={net.words}, "
        f"unseen word rows {net.unseen_words}); gestures from glu's synthetic generator"
    )
    return table, label


def prepare_world(config: SweepConfig) -> tuple[Any, str]:
    """The Affordance–Words network of a sweep (an inference engine) and a one-line label of its data."""
    from glu.bn import learn_bn, make_engine

    table, label = _experiments(config)
    return make_engine(learn_bn(table, unseen_words=config.network.unseen_words)), label


def saved_key(config: SweepConfig) -> dict[str, Any]:
    """What a sweep's tables depend on that can be named without computing anything (:mod:`glu.saved`): the
    format, the settings (the data folder by its contents, not its path) and the data's identity."""
    return _key(config.as_dict(), _experiments(config)[1])


def _key(settings: dict[str, Any], data_source: str) -> dict[str, Any]:
    settings = json.loads(json.dumps(settings))
    settings["network"]["data"] = settings["recognizer"]["file"] = None
    return {"format": [FORMAT, FORMAT_VERSION], "settings": settings, "data_source": data_source}


def export_saved(folder: str | os.PathLike, dest: str | os.PathLike, command: str) -> Path:
    """Write what notebook 11 reads of the finished sweep in ``folder``
    (:func:`~glu.studies.corpus_evaluation.tables.saved_subset`, Parquet with zstd) to ``dest``, with the
    sweep's ``sweep.json`` and ``summary.json`` and a :mod:`glu.saved` key file (``command``: how to
    regenerate it). Returns ``dest``.

    They are one set with two markers (:func:`glu.files.marked_set`): ``summary.json``, which
    :func:`~glu.studies.corpus_evaluation.tables.read_tables` needs, and the key file, which
    :func:`glu.saved.find` needs. Both are removed first and written last, every file through a temporary
    one, so an error or an interrupt while an existing ``dest`` is rewritten leaves one that both refuse,
    never new tables beside old ones under the old key. Other files in ``dest`` are left as they are."""
    from glu.saved import KEY_FILE, write_key
    from glu.studies.corpus_evaluation.tables import SUMMARY_FILE, read_tables, saved_subset

    folder, dest = Path(folder), Path(dest)
    provenance = json.loads((folder / "sweep.json").read_text(encoding="utf-8"))
    tables = saved_subset(read_tables(folder))
    dest.mkdir(parents=True, exist_ok=True)
    with marked_set(dest, SUMMARY_FILE, KEY_FILE):
        for (name, _), df in zip(TABLES, tables[:5], strict=True):
            df = df.copy()
            df.attrs = {}
            with atomic_path(dest / f"{name}.parquet", suffix=".parquet") as tmp:
                df.to_parquet(tmp, index=False, compression="zstd")
        atomic_write_json(dest / "sweep.json", provenance)
        # the per-cell summary ("overall", "best") is the sweep's own report: the notebook computes its own
        atomic_write_json(
            dest / SUMMARY_FILE, {k: v for k, v in tables.summary.items() if k not in ("overall", "best")}
        )
        key = _key(provenance["settings"], provenance["data_source"])
        write_key(dest, key, command, computed_by=provenance.get("made_with"))
    return dest


NOTEBOOK = "11_corpus_evaluation"
"""The notebook whose saved tables live in ``sweeps/11_corpus_evaluation/`` (:mod:`glu.saved`)."""


def notebook_tables(
    config: SweepConfig, workers: int | None = None, log: Callable[[str], None] = lambda s: None
) -> Path:
    """The folder of the tables of ``config``: saved ones with the same key (:func:`saved_key`), else a sweep
    run now into the cache (on a LocalCluster of ``workers``, or in this process for None) and kept there.
    :func:`glu.studies.corpus_evaluation.tables.read_tables` reads either."""
    from glu.saved import KEY_FILE, cache_folder, cache_key, find, write_key

    key = saved_key(config)
    found = find(NOTEBOOK, key)
    if found is not None:
        return found
    out = cache_folder(NOTEBOOK, key)
    log(f"no saved tables for these settings and data: running the sweep into {out}")
    with marked_set(out, KEY_FILE):  # the key vouches for the sweep's tables: written once they are
        run_sweep(
            config, out, scheduler=None if workers else SYNCHRONOUS, workers=workers, progress=False, log=log
        )
        write_key(out, cache_key(key), f"glu run {NOTEBOOK} (these parameters)")
    return out


def prepare(config: SweepConfig, out: Path, log: Callable[[str], None]) -> tuple[Evaluator, dict[str, Any]]:
    """The evaluator (networks learned, recognisers trained or loaded, calibrated) and the sweep's
    provenance."""
    from glu.studies.corpus_evaluation.evaluation import Replication, target_tables

    engine, label = prepare_world(config)
    bn = engine.bn
    recognizers = robots.recognizers(config, out, log)
    calibrations, fits = robots.calibrations(config, recognizers)
    learned = robots.learned_networks(config, engine)
    generating = target_tables(engine, config.evaluation)
    replications = []
    for k, recs in enumerate(recognizers):
        tables = {"generating": generating}
        for n, net in learned[k].items():
            tables[f"learned-{n}"] = target_tables(net, config.evaluation)
        scorers = {f: robots.scorer(rec) for f, rec in recs.items()}
        replications.append(Replication(scorers, calibrations[k], tables))
    evaluator = Evaluator(
        engine,
        tuple(replications),
        tuple(config.readings),
        config.evaluation,
        config.seed,
        config.chunk_size,
        config.scenario,
        config.gestures,
        {v: config.views[v] for v in config.viewpoints},
    )
    # what the numbers depend on: the settings (where the data and the recogniser file are does not
    # matter, what they hold does), the data, the networks, the models, glu's version
    digest = hashlib.sha256()
    for part in (
        json.dumps(_key(config.as_dict(), label)["settings"], sort_keys=True),
        label,
        json.dumps(bn.to_dict()),
        *(json.dumps(rec.to_dict()["models"]) for recs in recognizers for rec in recs.values()),
        __version__,
    ):
        digest.update(part.encode())
    provenance = {
        "format": FORMAT,
        "version": FORMAT_VERSION,
        "fingerprint": digest.hexdigest()[:32],
        "glu": __version__,
        "data_source": label,
        "settings": _public(config.as_dict()),
        "conditions": [asdict(c) for c in config.conditions],
        "readings": [asdict(r) for r in config.readings],
        "episodes_per_condition_and_seed": config.per_condition,
        "episodes": config.n_episodes,
        "statistics": len(evaluator.columns),
        "calibration": fits.to_dict("records"),
        "made_with": made_with(),
    }
    return evaluator, provenance


def _public(settings: dict[str, Any]) -> dict[str, Any]:
    """The settings without machine paths (a data folder or a recogniser file is named by its last part)."""
    out = json.loads(json.dumps(settings))
    for section, key in (("network", "data"), ("recognizer", "file")):
        v = out[section].get(key)
        if v and v != "synthetic":
            out[section][key] = Path(v).name
    return out


# ------------------------------------------------------------------------------------------ the tasks
def compute_chunk(evaluator: Evaluator, index: int, condition: Condition, chunk: int, n: int) -> tuple:
    """One task (run on a worker): one chunk of episodes of ``condition`` for every recogniser seed,
    scored under every reading, on one BLAS thread.

    Returns (index, chunk, n, sums of shape (R, B + 1, K) summed over the seeds, each seed's plain sums
    of shape (n_seeds, R, K), CPU seconds).
    """
    import scipy.ndimage  # noqa: F401 - loaded before the limit, which binds only libraries already loaded
    from threadpoolctl import threadpool_limits

    t0 = time.process_time()
    total, own = None, []
    with threadpool_limits(1):
        for k in range(len(evaluator.replications)):  # one seed's sums in memory at a time
            sums = evaluator.run_chunk(condition, k, chunk, n)
            total = sums if total is None else total + sums
            own.append(sums[:, 0].copy())
    return index, chunk, n, total, np.stack(own), time.process_time() - t0


# ------------------------------------------------------------------------------------------ the sweep
def run_sweep(
    config: SweepConfig,
    out: str | os.PathLike,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool | None = None,
    max_chunks: int | None = None,
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True),
) -> SweepResult:
    """Run (or resume) a sweep into the folder ``out`` and write its tables (see the module docstring).

    Parameters
    ----------
    config : the settings
    out : the output folder (created; a folder holding a sweep with other settings is refused)
    scheduler : None (a LocalCluster), a Dask address ``tcp://host:port``, or ``"synchronous"``
    workers : LocalCluster worker processes (default: one per core available)
    progress : show a progress bar (None: only on a terminal)
    max_chunks : run at most this many tasks now (a task is one chunk of episodes of one condition, for
        every recogniser seed and reading); the rest on a later run; tables are written only when every
        chunk is done
    log : where one-line messages go
    """
    t0 = time.perf_counter()
    check_scheduler(scheduler)
    if scheduler not in (None, SYNCHRONOUS):
        check_reachable(scheduler)  # before any work: an unreachable cluster is bad input, said at once
    out = Path(out)
    evaluator, provenance = _open_folder(config, out, log)
    for stale in (out / "chunks").glob(".c*.npz*"):  # a write cut short by a hard kill (never a whole chunk)
        stale.unlink(missing_ok=True)
    conditions = config.conditions
    from glu.studies.corpus_evaluation.corpus import chunk_ranges

    chunks = chunk_ranges(config.per_condition, config.chunk_size)
    tasks = [
        (i, c, k, n)
        for i, c in enumerate(conditions)
        for k, n in chunks
        if not chunk_path(out, i, k).is_file()
    ]
    total = len(conditions) * len(chunks)
    todo = tasks if max_chunks is None else tasks[: max(int(max_chunks), 0)]
    reused = total - len(tasks)
    where = {None: "a LocalCluster", SYNCHRONOUS: "this process"}.get(scheduler, scheduler)
    log(
        f"glu evaluate: {config.n_episodes} episodes, {len(conditions)} conditions × "
        f"{config.recognizer_seeds} recogniser seeds × {len(config.readings)} readings, {total} chunks "
        f"({reused} already done), on {where}; {provenance['data_source']}"
    )
    cpu = _run_tasks(
        evaluator, todo, out, provenance["fingerprint"], scheduler, workers, progress, reused, total
    )
    computed = len(todo)
    if reused + computed < total:
        log(f"glu evaluate: {reused + computed} of {total} chunks done; run again to finish")
        empty = pd.DataFrame()
        return SweepResult(
            out, empty, empty, empty, empty, {}, computed, reused, time.perf_counter() - t0, cpu
        )
    tables = merge(out, config, evaluator, provenance)
    return SweepResult(out, *tables, computed, reused, time.perf_counter() - t0, cpu)


def _open_folder(config: SweepConfig, out: Path, log: Callable[[str], None]) -> tuple[Any, dict]:
    """The sweep's evaluator and provenance, with ``out`` created for it or checked to hold the same sweep
    (``sweep.json``'s fingerprint); bad settings or data found while preparing leave no new folder behind."""
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:
        evaluator, provenance = prepare(config, out, log)
        sweep_file = out / "sweep.json"
        if sweep_file.is_file():
            try:
                old = json.loads(sweep_file.read_text())
            except (OSError, ValueError):
                old = {}
            if not isinstance(old, dict) or old.get("fingerprint") != provenance["fingerprint"]:
                raise DataError(
                    f"{out} holds a sweep with other settings or data (sweep.json); "
                    "use another output folder or delete that one"
                )
        else:
            atomic_write_json(sweep_file, provenance)
    except BaseException:
        if created:
            shutil.rmtree(out, ignore_errors=True)
        raise
    return evaluator, provenance


def _save(out: Path, fingerprint: str, result: tuple, bar: Any) -> float:
    index, chunk, n, sums, own, cpu = result
    write_chunk(out, fingerprint, index, chunk, n, sums, own)
    bar.update(1)
    return cpu


def _run_tasks(evaluator, todo, out, fingerprint, scheduler, workers, progress, done, total) -> float:
    from tqdm import tqdm

    bar = tqdm(
        total=total,
        initial=done,
        unit="chunk",
        desc="glu evaluate",
        disable=None if progress is None else not progress,
        file=sys.stderr,
        dynamic_ncols=True,
    )
    try:
        if not todo:
            return 0.0
        if scheduler == SYNCHRONOUS:
            return sum(_save(out, fingerprint, compute_chunk(evaluator, *task), bar) for task in todo)
        return _run_on_dask(evaluator, todo, out, fingerprint, scheduler, workers, bar)
    finally:
        bar.close()


def _same(obj: Any) -> Any:
    return obj


class WorkerLostError(GluError):
    """A Dask worker died during the sweep (killed, out of memory); the finished chunks are kept."""


LOST_WORKER_ERRORS = frozenset(
    {"KilledWorker", "CommClosedError", "StreamClosedError", "FutureCancelledError"}
)
"""What dask.distributed raises for a task whose worker went away."""


def _worker_lost(e: BaseException) -> bool:
    return type(e).__name__ in LOST_WORKER_ERRORS


def _run_on_dask(evaluator, todo, out, fingerprint, scheduler, workers, bar) -> float:
    n = workers or available_cores()
    with dask_client(n, scheduler, silence_logs=logging.CRITICAL) as client:
        from distributed import as_completed

        cpu = 0.0
        # a task, not scattered data: a worker that dies takes its copy with it, and the cluster recomputes
        # a task's result where scattered data would be lost for good (the sweep then waited forever)
        shared = client.submit(_same, evaluator, pure=False, key=f"glu-evaluator-{fingerprint[:8]}")
        futures = [
            client.submit(
                compute_chunk,
                shared,
                *t,
                pure=False,
                key=f"glu-chunk-{t[0]}-{t[2]}-{fingerprint[:8]}",
            )
            for t in todo
        ]
        for fut in as_completed(futures):
            try:
                result = fut.result()
            except GluError:
                raise
            except Exception as e:
                for f in futures:
                    f.cancel()
                if _worker_lost(e):
                    raise WorkerLostError(
                        f"a Dask worker was lost (its process died or was killed) while computing a chunk "
                        f"({type(e).__name__}); the chunks finished so far are saved in {out}: run the same "
                        "command again to resume from them"
                    ) from None
                raise RuntimeError(
                    f"a sweep task failed on the cluster ({type(e).__name__}: {e}); "
                    "do the workers have glu installed, in the same version?"
                ) from e
            cpu += _save(out, fingerprint, result, bar)
        return cpu
