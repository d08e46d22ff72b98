"""The tables of a corpus sweep: its chunk files, merged in index order into metrics, differences,
reliability diagrams, each seed's estimates and a summary (:func:`merge`)."""

from __future__ import annotations

import json
import zipfile
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.files import atomic_path, atomic_write_json, atomic_write_text, marked_set
from glu.studies.corpus_evaluation.config import SweepConfig
from glu.studies.corpus_evaluation.evaluation import Evaluator
from glu.studies.corpus_evaluation.findings import ADJUSTMENT, DESIGN, verdicts_adjusted, winners
from glu.studies.corpus_evaluation.intervals import (
    block_frame,
    difference_block,
    difference_pairs,
    metric_block,
    metric_cells,
    metric_values,
    reliability_block,
    reliability_index,
    reliability_keys,
)
from glu.tidy import tidy

EXPERIMENT = "corpus_evaluation"
TABLES: tuple[tuple[str, str], ...] = (
    ("results", EXPERIMENT),
    ("differences", "corpus_differences"),
    ("reliability", "corpus_reliability"),
    ("seeds", "corpus_seeds"),
    ("calibration", "corpus_calibration"),
)
"""Each table of a sweep's folder: its file's stem (``.parquet``) and its experiment stamp."""
SUMMARY_FILE = "summary.json"
"""The summary of a sweep's folder, written after every table: :func:`read_tables` takes a folder without
it for a sweep not finished (or a rewrite of its tables cut short)."""
FILES = (*(f"{file}.parquet" for file, _ in TABLES), SUMMARY_FILE, "summary.csv")
CONDITION_FACTORS: tuple[str, ...] = ("effects", "action_prior")
"""The simulated conditions' factors that every table keeps apart (the noise and the viewpoint are also
pooled)."""


def chunk_path(out: Path, index: int, chunk: int) -> Path:
    """The file of one finished task of a sweep: condition ``index``'s chunk ``chunk``, in ``out/chunks/``."""
    return out / "chunks" / f"c{index:03d}-{chunk:06d}.npz"


def write_chunk(
    out: Path, fingerprint: str, index: int, chunk: int, n: int, sums: np.ndarray, own: np.ndarray
) -> None:
    """One task's sums: ``sums`` shape (R, B + 1, K) (row 0 the estimate), ``own`` each seed's plain sums
    (n_seeds, R, K). Each reading's replicates are stored apart, so the merge reads one reading at a time."""
    path = chunk_path(out, index, chunk)
    reps = {f"replicates{r}": sums[r, 1:].astype(np.float32) for r in range(len(sums))}
    with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as f:
        np.savez(
            f,
            estimate=sums[:, 0],
            seeds=own,
            meta=np.array(
                json.dumps(
                    {
                        "fingerprint": fingerprint,
                        "condition": index,
                        "chunk": chunk,
                        "n": n,
                        "readings": len(sums),
                    }
                )
            ),
            **reps,
        )


def read_chunk(
    path: Path, fingerprint: str, reading: int | None = None
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """The estimate (R, K), the replicates of one reading (B, K) (None without ``reading``) and each seed's
    sums (n_seeds, R, K) of a chunk file."""
    try:
        with np.load(path) as z:
            meta = json.loads(str(z["meta"]))
            estimate, seeds = z["estimate"], z["seeds"]
            replicates = None if reading is None else z[f"replicates{reading}"]
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
DIFFERENCE_GROUPS: tuple[tuple[str, ...], ...] = (("viewpoint",), ("noise",), ())
"""The poolings the paired differences are computed at: per viewpoint, per noise level, and pooled over
both; each is a family of its own for the multiplicity adjustment."""
ORDER = [*DESIGN, "noise", "viewpoint"]


def _condition_sums(
    out: Path, config: SweepConfig, provenance: dict[str, Any], reading: int, K: int, B: int
) -> list[np.ndarray]:
    """One reading's summed statistics of each condition, arrays of shape (B + 1, K)."""
    from glu.studies.corpus_evaluation.corpus import chunk_ranges

    sums = []
    for i in range(len(config.conditions)):
        total = np.zeros((B + 1, K))
        for k, _ in chunk_ranges(config.per_condition, config.chunk_size):
            est, reps, _ = read_chunk(chunk_path(out, i, k), provenance["fingerprint"], reading)
            total[0] += est[reading]
            total[1:] += reps.astype(np.float64)
        sums.append(total)
    return sums


def _pooled_groups(conditions: Sequence[Any], by: Sequence[str]) -> list[tuple[tuple, list[int]]]:
    """The conditions of each group that keeps :data:`CONDITION_FACTORS` and ``by`` (the rest pooled), in
    sorted order of the group's values."""
    groups: dict[tuple, list[int]] = {}
    for i, c in enumerate(conditions):
        groups.setdefault(tuple(getattr(c, f) for f in (*CONDITION_FACTORS, *by)), []).append(i)
    return sorted(groups.items(), key=lambda kv: tuple(str(x) if isinstance(x, str) else x for x in kv[0]))


def _reading_tables(
    sums: list[np.ndarray], config: SweepConfig, cols: pd.DataFrame, cells: Any, pairs: Any
) -> dict[str, list[pd.DataFrame]]:
    """One reading's results, differences and reliability rows at every pooling, from its conditions'
    sums."""
    conditions = config.conditions
    out: dict[str, list[pd.DataFrame]] = {"results": [], "differences": [], "reliability": []}
    rel_keys, rel_index = reliability_keys(cols), reliability_index(cols)
    for name, groups, keys in (
        ("results", GROUPS, cells.keys),
        ("differences", {k: GROUPS[k] for k in DIFFERENCE_GROUPS}, pairs.keys),
        ("reliability", {k: GROUPS[k] for k in (("viewpoint",), ())}, rel_keys),
    ):
        for by, fill in groups.items():
            blocks = []
            for key, idx in _pooled_groups(conditions, by):
                S = np.sum([sums[i] for i in idx], axis=0)
                if name == "results":
                    blocks.append((key, metric_block(S, cells)))
                elif name == "differences":
                    blocks.append((key, difference_block(S, cells, pairs)))
                else:
                    blocks.append((key, reliability_block(S[0], rel_index)))
            part = block_frame(keys, [*CONDITION_FACTORS, *by], blocks)
            out[name].append(part.assign(**fill))
    return out


def adjust_families(diffs: pd.DataFrame, families: Sequence[str]) -> pd.DataFrame:
    """``diffs`` with ``p_adjusted`` (:data:`ADJUSTMENT` within each family: the rows that share the values
    of ``families``) and ``verdict_adjusted`` (a verdict only where the adjusted p-value is at most α, in the
    direction of the difference)."""
    from glu.stats import adjust

    out = diffs.copy()
    out["p_adjusted"] = np.nan
    keys = [out[f].fillna(-1.0) if out[f].dtype.kind == "f" else out[f] for f in families]
    for _, idx in out.groupby(keys, sort=False, dropna=False).groups.items():
        out.loc[idx, "p_adjusted"] = adjust(out.loc[idx, "p_value"].to_numpy(), ADJUSTMENT)
    out["verdict_adjusted"] = verdicts_adjusted(out)
    return out


def merge(
    out: Path, config: SweepConfig, evaluator: Evaluator, provenance: dict[str, Any]
) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, pd.DataFrame, dict[str, Any]]:
    """Merge the chunks (in index order) and write every table of the output folder.

    One reading at a time, so that memory holds the sums of one reading, never of the whole grid. The tables
    and ``summary.csv`` are one set with :data:`SUMMARY_FILE` (:func:`glu.files.marked_set`): it is removed
    before the first table is written and written last, so a rewrite of a finished sweep's tables cut short
    leaves a folder :func:`read_tables` refuses, never new tables beside old ones.
    """
    from glu.studies.corpus_evaluation.corpus import chunk_ranges

    cols = evaluator.columns
    K, B = len(cols), evaluator.settings.bootstrap
    readings, conditions = config.readings, config.conditions
    n_seeds = len(evaluator.replications)
    own = np.zeros((len(conditions), n_seeds, len(readings), K))
    for i in range(len(conditions)):
        for k, _ in chunk_ranges(config.per_condition, config.chunk_size):
            own[i] += read_chunk(chunk_path(out, i, k), provenance["fingerprint"])[2]
    tables: dict[str, list[pd.DataFrame]] = {"results": [], "differences": [], "reliability": [], "seeds": []}
    cells = metric_cells(cols)
    pairs = difference_pairs(cells)
    for r, reading in enumerate(readings):
        design = asdict(reading)
        sums = _condition_sums(out, config, provenance, r, K, B)
        for name, parts in _reading_tables(sums, config, cols, cells, pairs).items():
            for part in parts:
                part = part.assign(**design)
                tables[name].append(part[ORDER + [c for c in part.columns if c not in ORDER]])
        for effects in config.effects:  # each seed's estimates, pooled over noise and views
            for prior in config.action_prior:
                idx = [
                    i for i, c in enumerate(conditions) if c.action_prior == prior and c.effects == effects
                ]
                for k in range(n_seeds):
                    vals = metric_values(own[idx, k, r].sum(axis=0)[None, :], cells)[0]
                    tables["seeds"].append(
                        cells.keys.assign(
                            effects=effects, action_prior=prior, recognizer_seed=k, estimate=vals, **design
                        )
                    )
    table, diffs, rel = (
        pd.concat(tables[n], ignore_index=True) for n in ("results", "differences", "reliability")
    )
    diffs = adjust_families(diffs, ["noise", "viewpoint"])
    seeds = pd.concat(tables["seeds"], ignore_index=True)
    seeds = seeds[[*DESIGN, "recognizer_seed", "target", "strategy", "fraction", "metric", "estimate"]]
    calibration = pd.DataFrame(provenance.get("calibration", []))
    params = provenance["settings"]
    source = provenance["data_source"]
    # summarised before the tables are stamped: pandas deep-copies a frame's attrs (here every setting of the
    # sweep) on every row or column it hands out, which made summarize several times slower
    summary = summarize(table, diffs, provenance)
    for df, (_, name) in zip((table, diffs, rel, seeds, calibration), TABLES, strict=True):
        tidy(df, name, source, **params)
    head = pd.DataFrame(summary["overall"])
    with marked_set(out, SUMMARY_FILE):
        for df, (file, _) in zip((table, diffs, rel, seeds, calibration), TABLES, strict=True):
            with atomic_path(out / f"{file}.parquet", suffix=".parquet") as tmp:
                df.to_parquet(tmp, index=False)
        text = head.to_csv(index=False, float_format="%.6g", lineterminator="\n")
        atomic_write_text(out / "summary.csv", text)
        atomic_write_json(out / SUMMARY_FILE, summary)
    return table, diffs, rel, seeds, summary


SAVED_METRICS: tuple[str, ...] = ("accuracy", "log_loss", "ece")
"""The metrics the saved tables keep (the notebook shows no Brier score)."""


def saved_subset(tables: SweepTables) -> SweepTables:
    """What notebook 11 reads of a sweep's tables, and so what ``sweeps/`` keeps of it: the metrics of
    :data:`SAVED_METRICS` per viewpoint, per noise level and pooled (not both at once); the paired
    differences of the findings' pairs (:data:`~glu.studies.corpus_evaluation.findings.FINDINGS`) at
    every pooling, and of every pair on the front view at the full gesture (each cell's winner); the seeds'
    estimates at the full gesture; the reliability diagrams and the calibrations whole."""
    from glu.studies.corpus_evaluation.findings import FINDINGS

    m = tables.metrics
    keep = m.metric.isin(SAVED_METRICS) & ~((m.viewpoint != "all") & m.noise.notna())
    d = tables.differences
    d = d[d.metric.isin(SAVED_METRICS)]
    wanted = np.zeros(len(d), dtype=bool)
    for f in FINDINGS:
        for a, b in ((f.strategy, f.baseline), (f.baseline, f.strategy)):
            same = (d.target == f.target) & (d.metric == f.metric)
            wanted |= (same & (d.strategy == a) & (d.baseline == b)).to_numpy()
    full = np.isclose(d.fraction, d.fraction.max())
    winners = (full & (d.viewpoint == "front") & d.noise.isna()).to_numpy()
    seeds = tables.seeds[np.isclose(tables.seeds.fraction, tables.seeds.fraction.max())]
    return tables._replace(metrics=m[keep], differences=d[wanted | winners], seeds=seeds)


class SweepTables(NamedTuple):
    """The tables of a finished sweep (:func:`read_tables`)."""

    metrics: pd.DataFrame
    differences: pd.DataFrame
    reliability: pd.DataFrame
    seeds: pd.DataFrame
    calibration: pd.DataFrame
    summary: dict[str, Any]


def read_tables(folder: str | Path) -> SweepTables:
    """The tables a finished sweep wrote to ``folder``, stamped as :func:`merge` stamps them; a folder
    without :data:`SUMMARY_FILE` (a sweep not finished, or a rewrite of its tables cut short) is refused in
    one line (:class:`DataError`)."""
    folder = Path(folder)
    try:
        summary = json.loads((folder / SUMMARY_FILE).read_text(encoding="utf-8"))
        frames = [pd.read_parquet(folder / f"{file}.parquet") for file, _ in TABLES]
    except (OSError, ValueError) as e:
        raise DataError(f"{folder}: not the output folder of a finished `glu evaluate` ({e})") from None
    if not isinstance(summary, dict) or summary.get("experiment") != EXPERIMENT:
        raise DataError(f"{folder}: summary.json is not a corpus evaluation's")
    for df, (_, name) in zip(frames, TABLES, strict=True):
        tidy(df, name, summary["data_source"], **summary["parameters"])
    return SweepTables(*frames, summary)


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
