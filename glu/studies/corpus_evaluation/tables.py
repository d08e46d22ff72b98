"""The tables of a corpus sweep: its chunk files, merged in index order into metrics, differences,
reliability diagrams, each seed's estimates and a summary (:func:`merge`)."""

from __future__ import annotations

import json
import zipfile
from dataclasses import asdict
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.files import atomic_path, atomic_write_json, atomic_write_text
from glu.studies.corpus_evaluation.config import SweepConfig
from glu.studies.corpus_evaluation.evaluation import Evaluator
from glu.studies.corpus_evaluation.findings import DESIGN, winners
from glu.studies.corpus_evaluation.intervals import (
    metric_cells,
    metric_values,
    metrics,
    paired_differences,
    reliability,
)
from glu.tidy import tidy

EXPERIMENT = "corpus_evaluation"
FILES = (
    "sums.parquet",
    "results.parquet",
    "differences.parquet",
    "reliability.parquet",
    "seeds.parquet",
    "calibration.parquet",
    "summary.json",
    "summary.csv",
)


def chunk_path(out: Path, index: int, chunk: int) -> Path:
    return out / "chunks" / f"c{index:03d}-{chunk:06d}.npz"


def write_chunk(
    out: Path, fingerprint: str, index: int, chunk: int, n: int, sums: np.ndarray, own: np.ndarray
) -> None:
    """One task's sums: ``sums`` shape (R, B + 1, K) (row 0 the estimate), ``own`` each seed's plain sums
    (n_seeds, R, K)."""
    path = chunk_path(out, index, chunk)
    with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as f:
        np.savez(
            f,
            estimate=sums[:, 0],
            replicates=sums[:, 1:].astype(np.float32),
            seeds=own,
            meta=np.array(
                json.dumps({"fingerprint": fingerprint, "condition": index, "chunk": chunk, "n": n})
            ),
        )


def read_chunk(path: Path, fingerprint: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The estimate (R, K), the replicates (R, B, K) and each seed's sums (n_seeds, R, K) of a chunk file."""
    try:
        with np.load(path) as z:
            meta = json.loads(str(z["meta"]))
            estimate, replicates, seeds = z["estimate"], z["replicates"], z["seeds"]
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as e:  # a truncated file: BadZipFile
        raise DataError(f"{path}: unreadable chunk ({e}); delete it and run the sweep again") from None
    if meta.get("fingerprint") != fingerprint:
        raise DataError(
            f"{path}: this chunk belongs to another sweep; delete it or use another output folder"
        )
    return estimate, replicates, seeds


GROUPS: dict[tuple[str, ...], dict[str, Any]] = {
    ("noise", "viewpoint"): {},
    ("noise",): {"viewpoint": "all"},
    ("viewpoint",): {"noise": np.nan},
    (): {"noise": np.nan, "viewpoint": "all"},
}
"""How the noise levels and viewpoints are pooled (every pooling keeps the design's factors)."""
ORDER = [*DESIGN, "noise", "viewpoint"]


def merge(
    out: Path, config: SweepConfig, evaluator: Evaluator, provenance: dict[str, Any]
) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, pd.DataFrame, dict[str, Any]]:
    """Merge the chunks (in index order) and write every table of the output folder.

    One reading at a time, so that memory holds the sums of one reading, never of the whole grid.
    """
    from glu.studies.corpus_evaluation.corpus import chunk_ranges

    cols = evaluator.columns
    K, B = len(cols), evaluator.settings.bootstrap
    readings, conditions = config.readings, config.conditions
    n_seeds = len(evaluator.replications)
    totals = np.zeros((len(conditions), len(readings), B + 1, K))
    own = np.zeros((len(conditions), n_seeds, len(readings), K))
    for i in range(len(conditions)):
        for k, _ in chunk_ranges(config.per_condition, config.chunk_size):
            est, reps, seeds = read_chunk(chunk_path(out, i, k), provenance["fingerprint"])
            totals[i, :, 0] += est
            totals[i, :, 1:] += reps.astype(np.float64)
            own[i] += seeds
    tables: dict[str, list[pd.DataFrame]] = {"results": [], "differences": [], "reliability": [], "seeds": []}
    sums_parts = []
    cells = metric_cells(cols)
    for r, reading in enumerate(readings):
        design = asdict(reading)
        frames = []
        for i, c in enumerate(conditions):
            f = pd.DataFrame(totals[i, r], columns=[f"s{j}" for j in range(K)])
            f.insert(0, "replicate", np.arange(B + 1))
            f.insert(0, "viewpoint", c.viewpoint)
            f.insert(0, "noise", c.noise)
            f.insert(0, "action_prior", c.action_prior)
            frames.append(f)
        sums = pd.concat(frames, ignore_index=True)
        sums_parts.append(sums.assign(**design))
        for name, fn, groups in (
            ("results", metrics, GROUPS),
            (
                "differences",
                paired_differences,
                {k: GROUPS[k] for k in (("noise", "viewpoint"), ("viewpoint",), ())},
            ),
            ("reliability", reliability, {k: GROUPS[k] for k in (("noise", "viewpoint"), ())}),
        ):
            for by, fill in groups.items():
                part = fn(sums, cols, ["action_prior", *by]).assign(**fill, **design)
                tables[name].append(part[ORDER + [c for c in part.columns if c not in ORDER]])
        for prior in config.action_prior:  # each seed's estimates, pooled over noise and views
            idx = [i for i, c in enumerate(conditions) if c.action_prior == prior]
            for k in range(n_seeds):
                vals = metric_values(own[idx, k, r].sum(axis=0)[None, :], cells)[0]
                tables["seeds"].append(
                    cells.keys.assign(action_prior=prior, recognizer_seed=k, estimate=vals, **design)
                )
    table, diffs, rel = (
        pd.concat(tables[n], ignore_index=True) for n in ("results", "differences", "reliability")
    )
    seeds = pd.concat(tables["seeds"], ignore_index=True)
    seeds = seeds[[*DESIGN, "recognizer_seed", "target", "strategy", "fraction", "metric", "estimate"]]
    calibration = pd.DataFrame(
        provenance.get("calibration", []), columns=["recognizer_seed", "fraction", "beta", "n_gestures"]
    )
    params = provenance["settings"]
    source = provenance["data_source"]
    # summarised before the tables are stamped: pandas deep-copies a frame's attrs (here every setting of the
    # sweep) on every row or column it hands out, which made summarize several times slower
    summary = summarize(table, diffs, provenance)
    for df, name in (
        (table, EXPERIMENT),
        (diffs, "corpus_differences"),
        (rel, "corpus_reliability"),
        (seeds, "corpus_seeds"),
        (calibration, "corpus_calibration"),
    ):
        tidy(df, name, source, **params)
    _write_parquet(out / "sums.parquet", pd.concat(sums_parts, ignore_index=True))
    _write_parquet(out / "results.parquet", table)
    _write_parquet(out / "differences.parquet", diffs)
    _write_parquet(out / "reliability.parquet", rel)
    _write_parquet(out / "seeds.parquet", seeds)
    _write_parquet(out / "calibration.parquet", calibration)
    atomic_write_json(out / "summary.json", summary)
    head = pd.DataFrame(summary["overall"])
    atomic_write_text(out / "summary.csv", head.to_csv(index=False, float_format="%.6g", lineterminator="\n"))
    return table, diffs, rel, seeds, summary


class SweepTables(NamedTuple):
    """The tables of a finished sweep (:func:`read_tables`)."""

    metrics: pd.DataFrame
    differences: pd.DataFrame
    reliability: pd.DataFrame
    seeds: pd.DataFrame
    calibration: pd.DataFrame
    summary: dict[str, Any]


def read_tables(folder: str | Path) -> SweepTables:
    """The tables a finished sweep wrote to ``folder``, stamped as :func:`merge` stamps them."""
    folder = Path(folder)
    names = ("results", "differences", "reliability", "seeds", "calibration")
    try:
        summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        frames = [pd.read_parquet(folder / f"{n}.parquet") for n in names]
    except (OSError, ValueError) as e:
        raise DataError(f"{folder}: not the output folder of a finished `glu evaluate` ({e})") from None
    if not isinstance(summary, dict) or summary.get("experiment") != EXPERIMENT:
        raise DataError(f"{folder}: summary.json is not a corpus evaluation's")
    experiments = (
        EXPERIMENT,
        "corpus_differences",
        "corpus_reliability",
        "corpus_seeds",
        "corpus_calibration",
    )
    for df, name in zip(frames, experiments, strict=True):
        tidy(df, name, summary["data_source"], **summary["parameters"])
    return SweepTables(*frames, summary)


def _write_parquet(path: Path, df: pd.DataFrame) -> None:
    with atomic_path(path, suffix=".parquet") as tmp:
        df.to_parquet(tmp, index=False)


def summarize(table: pd.DataFrame, diffs: pd.DataFrame, provenance: dict[str, Any]) -> dict[str, Any]:
    """The tidy summary: overall metrics at the full gesture (pooled over noise levels and viewpoints),
    and the winner of each cell of the design (:func:`winners`)."""
    full = table["fraction"].max() if table["fraction"].notna().any() else np.nan
    overall = table[(table.viewpoint == "all") & table.noise.isna() & (table.fraction == full)]
    rows = [
        {
            k: (None if isinstance(v, float) and not np.isfinite(v) else v)
            for k, v in r.items()
            if k not in ("noise", "viewpoint")
        }
        for r in overall.to_dict("records")
    ]
    best = winners(table, diffs, full).to_dict("records")
    return {
        "experiment": EXPERIMENT,
        "data_source": provenance["data_source"],
        "fingerprint": provenance["fingerprint"],
        "episodes": provenance["episodes"],
        "conditions": provenance["conditions"],
        "readings": provenance["readings"],
        "parameters": provenance["settings"],
        "files": list(FILES),
        "overall": rows,
        "best": best,
    }
