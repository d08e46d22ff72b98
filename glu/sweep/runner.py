"""Run a corpus sweep as Dask tasks, resumably, and merge the chunks into tables.

The grid of a sweep is strategy × noise × observed fraction × viewpoint × seed chunks. One **task** is one
chunk of episodes in one condition (noise, viewpoint): it simulates the episodes once and scores them at
every fraction with every strategy, since those share the gesture and its forward pass
(:meth:`glu.experiments.evaluation.Evaluator.run_chunk`). Tasks run

* on a ``LocalCluster`` sized to the machine (one single-threaded worker process per core) by default;
* on an existing cluster with ``scheduler="tcp://host:8786"`` (``dask scheduler`` and ``dask worker``,
  see the README); the workers need glu installed;
* in this process, one after another, with ``scheduler="synchronous"`` (tests, notebooks, debugging).

Each finished chunk is written by this process (workers need no shared disk) to ``OUT/chunks/`` through
a temporary file and a rename, so an interrupted sweep leaves only whole chunks; running it again computes
only the missing ones. A chunk's numbers depend only on the settings, the seed and its index, and chunks
are merged in index order, so the same settings give the same tables on any cluster.

The output folder::

    OUT/sweep.json          the settings, the data source and a fingerprint of everything behind the numbers
    OUT/recognizer.json     the gesture HMMs used (trained once, reused on resume)
    OUT/chunks/*.npz        the summed statistics of each chunk (estimate and bootstrap replicates)
    OUT/sums.parquet        the chunks merged: one row per condition and replicate
    OUT/results.parquet     THE table: every metric with its 95 % interval, per condition, pooled over the
                            viewpoints (viewpoint "all"), over the noise levels (noise NaN), and both
    OUT/differences.parquet paired differences between strategies, with intervals
    OUT/reliability.parquet the effect's reliability diagrams
    OUT/summary.json, OUT/summary.csv   the tidy summary: the overall metrics at the full gesture, and
                            which strategy is best for each target and metric
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
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
from glu.errors import DataError, GluError, ModelError
from glu.experiments.corpus import Condition
from glu.experiments.evaluation import Evaluator
from glu.files import atomic_write_json
from glu.schema import ACTIONS
from glu.sweep.config import SweepConfig
from glu.sweep.tables import chunk_path, merge, write_chunk

FORMAT = "glu-sweep"
FORMAT_VERSION = 1
SYNCHRONOUS = "synchronous"
ADDRESS = re.compile(r"^(tcp|tls|ws|wss)://[^\s/]+:\d+/?$")
RECOGNIZER_SEED_OFFSET = 5000
"""The recogniser's training gestures are drawn with ``seed + 5000``, apart from the episodes."""


def check_scheduler(address: str | None) -> str | None:
    """``address`` if it is None, ``synchronous`` or a Dask address ``tcp://host:port``; else DataError."""
    if address is None or address == SYNCHRONOUS or ADDRESS.match(address):
        return address
    raise DataError(
        f"--scheduler {address!r}: expected a Dask scheduler address such as tcp://127.0.0.1:8786, "
        f"or '{SYNCHRONOUS}' to run in this process"
    )


@dataclass
class SweepResult:
    """What a sweep produced: the folder, its tables, and how much was computed now."""

    out: Path
    metrics: pd.DataFrame
    differences: pd.DataFrame
    reliability: pd.DataFrame
    summary: dict[str, Any]
    computed: int
    reused: int
    seconds: float
    task_cpu_seconds: float = 0.0
    """CPU time the tasks computed now took, summed over workers (the parallel part of ``seconds``)."""


# ------------------------------------------------------------------------------------------ preparing
def prepare_world(config: SweepConfig) -> tuple[Any, str]:
    """The Affordance–Words network of a sweep (an inference engine) and a one-line label of its data."""
    from glu.bn import InferenceEngine, learn_bn
    from glu.data import load_experiments, resolve_data

    net = config.network
    source = resolve_data(net.data)
    table = load_experiments(source, net.words)
    bn = learn_bn(table, unseen_words=net.unseen_words)
    label = (
        f"{source.describe()}: network learned from {len(table)} experiments (words={net.words}, "
        f"unseen word rows {net.unseen_words}); gestures from glu's synthetic generator"
    )
    return InferenceEngine(bn), label


def prepare(config: SweepConfig, out: Path, log: Callable[[str], None]) -> tuple[Evaluator, dict[str, Any]]:
    """The evaluator (network learned, recogniser trained or loaded) and the sweep's provenance."""
    from glu.hmm import BatchScorer

    engine, label = prepare_world(config)
    bn = engine.bn
    recognizer = _recognizer(config, out, log)
    missing = [a for a in ACTIONS if a not in recognizer.models]
    if missing:
        raise ModelError(
            f"the recogniser has no model for {', '.join(missing)}; it needs {', '.join(ACTIONS)}"
        )
    evaluator = Evaluator(
        engine,
        BatchScorer([recognizer.models[a] for a in ACTIONS]),
        config.evaluation,
        config.seed,
        config.chunk_size,
        config.scenario,
        config.gestures,
        {v: config.views[v] for v in config.viewpoints},
    )
    # what the numbers depend on: the settings (where the data and the recogniser file are does not
    # matter, what they hold does), the data, the network, the models, glu's version
    settings = config.as_dict()
    settings["network"]["data"] = settings["recognizer"]["file"] = None
    digest = hashlib.sha256()
    for part in (
        json.dumps(settings, sort_keys=True),
        label,
        json.dumps(bn.to_dict()),
        json.dumps(recognizer.to_dict()["models"]),
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
        "episodes_per_condition": config.per_condition,
        "episodes": config.n_episodes,
        "statistics": len(evaluator.columns),
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


def _recognizer(config: SweepConfig, out: Path, log: Callable[[str], None]) -> Any:
    from glu.gestures.corpus import synthetic_corpus
    from glu.gestures.recognizer import Recognizer, train_recognizer

    r = config.recognizer
    if r.file:
        return Recognizer.load(r.file)
    saved = out / "recognizer.json"
    recipe = {"sweep_recipe": {**asdict(r), "seed": config.seed}}
    if saved.is_file():
        try:
            rec = Recognizer.load(saved)
            if rec.meta.get("sweep_recipe") == recipe["sweep_recipe"]:
                return rec
        except ModelError:
            pass
    log(
        f"training the gesture HMMs on {r.n_per_action} synthetic gestures per action (Q={r.n_states}, M={r.n_mix})"
    )
    corpus = synthetic_corpus(r.n_per_action, config.seed + RECOGNIZER_SEED_OFFSET, noise=r.noise)
    by_action: dict[str, list[np.ndarray]] = {}
    for s in corpus:
        by_action.setdefault(s.action, []).append(s.xyz)
    meta = {**recipe, "data_source": corpus.description}
    rec = train_recognizer(by_action, r.training(), seed=config.seed, warn=False, meta=meta)
    rec.save(saved)
    return rec


# ------------------------------------------------------------------------------------------ the tasks
def compute_chunk(
    evaluator: Evaluator, indices: tuple[int, ...], conditions: tuple[Condition, ...], chunk: int, n: int
) -> tuple:
    """One task (run on a worker): one chunk of episodes, simulated once and scored for each of
    ``conditions`` (the same noise and viewpoint, other posteriors), on one BLAS thread."""
    import scipy.ndimage  # noqa: F401 - loaded before the limit, which binds only libraries already loaded
    from threadpoolctl import threadpool_limits

    t0 = time.process_time()
    with threadpool_limits(1):
        sums = evaluator.run_chunks(conditions, chunk, n)
    return indices, chunk, n, sums, time.process_time() - t0


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
    max_chunks : run at most this many tasks now (a task is one chunk of episodes, scored for every
        posterior); the rest on a later run; tables are written only when every chunk is done
    log : where one-line messages go
    """
    t0 = time.perf_counter()
    check_scheduler(scheduler)
    if scheduler not in (None, SYNCHRONOUS):
        _check_reachable(scheduler)  # before any work: an unreachable cluster is bad input, said at once
    out = Path(out)
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:  # bad settings or data found while preparing leave no new folder behind
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
    for stale in (out / "chunks").glob(".c*.npz*"):  # a write cut short by a hard kill (never a whole chunk)
        stale.unlink(missing_ok=True)
    conditions = config.conditions
    from glu.experiments.corpus import chunk_ranges

    chunks = chunk_ranges(config.per_condition, config.chunk_size)
    tasks, missing = [], 0
    for noise in config.noise:  # one task per (noise, viewpoint, chunk): the posteriors share the episodes
        for view in config.viewpoints:
            group = [
                (i, c) for i, c in enumerate(conditions) if (c.noise, c.viewpoint) == (float(noise), view)
            ]
            for k, n in chunks:
                todo_here = [(i, c) for i, c in group if not chunk_path(out, i, k).is_file()]
                if todo_here:
                    tasks.append((tuple(i for i, _ in todo_here), tuple(c for _, c in todo_here), k, n))
                    missing += len(todo_here)
    total = len(conditions) * len(chunks)
    todo = tasks if max_chunks is None else tasks[: max(int(max_chunks), 0)]
    reused = total - missing
    where = {None: "a LocalCluster", SYNCHRONOUS: "this process"}.get(scheduler, scheduler)
    log(
        f"glu evaluate: {config.n_episodes} episodes, {len(conditions)} conditions, {total} chunks "
        f"({reused} already done), on {where}; {provenance['data_source']}"
    )
    cpu = _run_tasks(
        evaluator, todo, out, provenance["fingerprint"], scheduler, workers, progress, reused, total
    )
    computed = sum(len(t[0]) for t in todo)
    if reused + computed < total:
        log(f"glu evaluate: {reused + computed} of {total} chunks done; run again to finish")
        empty = pd.DataFrame()
        return SweepResult(out, empty, empty, empty, {}, computed, reused, time.perf_counter() - t0, cpu)
    tables = merge(out, config, evaluator, provenance)
    return SweepResult(out, *tables, computed, reused, time.perf_counter() - t0, cpu)


def _save(out: Path, fingerprint: str, result: tuple, bar: Any) -> float:
    indices, chunk, n, sums, cpu = result
    for index, s in zip(indices, sums, strict=True):
        write_chunk(out, fingerprint, index, chunk, n, s)
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


def _check_reachable(address: str, timeout: float = 10.0) -> None:
    """DataError unless something accepts TCP connections at the scheduler's host and port."""
    import socket

    host, _, port = address.split("://", 1)[1].rstrip("/").rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
            pass
    except OSError as e:
        raise DataError(f"cannot reach the Dask scheduler at {address}: {e.strerror or e}") from None


def _run_on_dask(evaluator, todo, out, fingerprint, scheduler, workers, bar) -> float:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        from glu.errors import MissingDependencyError

        raise MissingDependencyError(
            "running on Dask needs dask.distributed, which the plain `pip install glu` leaves out; "
            "install it with: pip install 'glu[dask]'"
        ) from None

    cluster = None
    try:
        if scheduler is None:
            from glu.machine import available_cores

            n = workers or available_cores()
            cluster = LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",
                silence_logs=logging.ERROR,
            )
            client = Client(cluster)
        else:
            try:
                client = Client(scheduler, timeout="30s")
            except (OSError, TimeoutError) as e:
                raise DataError(f"cannot reach the Dask scheduler at {scheduler}: {e}") from None
    except BaseException:
        if cluster is not None:
            cluster.close()
        raise
    try:
        cpu = 0.0
        shared = client.scatter(evaluator, broadcast=True)
        futures = [
            client.submit(
                compute_chunk,
                shared,
                *t,
                pure=False,
                key=f"glu-chunk-{'-'.join(map(str, t[0]))}-{t[2]}-{fingerprint[:8]}",
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
                raise RuntimeError(
                    f"a sweep task failed on the cluster ({type(e).__name__}: {e}); "
                    "do the workers have glu installed, in the same version?"
                ) from e
            cpu += _save(out, fingerprint, result, bar)
        return cpu
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
