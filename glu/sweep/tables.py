"""The tables of a corpus sweep: its chunk files, merged in index order into metrics, differences,
reliability diagrams and a summary (:func:`merge`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.experiments.common import tidy
from glu.experiments.evaluation import Evaluator
from glu.experiments.intervals import HIGHER_IS_BETTER, metrics, paired_differences, reliability
from glu.files import atomic_path, atomic_write_json, atomic_write_text
from glu.sweep.config import SweepConfig

EXPERIMENT = "corpus_evaluation"
REFERENCES = ("true_action",)
"""Strategies that are references (a ceiling), not candidates for "best" in the summary."""
FILES = (
    "sums.parquet",
    "results.parquet",
    "differences.parquet",
    "reliability.parquet",
    "summary.json",
    "summary.csv",
)


def chunk_path(out: Path, index: int, chunk: int) -> Path:
    return out / "chunks" / f"c{index:03d}-{chunk:06d}.npz"


def write_chunk(out: Path, fingerprint: str, index: int, chunk: int, n: int, sums: np.ndarray) -> None:
    path = chunk_path(out, index, chunk)
    with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as f:
        np.savez(
            f,
            estimate=sums[0],
            replicates=sums[1:].astype(np.float32),
            meta=np.array(
                json.dumps({"fingerprint": fingerprint, "condition": index, "chunk": chunk, "n": n})
            ),
        )


def read_chunk(path: Path, fingerprint: str) -> tuple[np.ndarray, np.ndarray]:
    try:
        with np.load(path) as z:
            meta = json.loads(str(z["meta"]))
            estimate, replicates = z["estimate"], z["replicates"]
    except (OSError, ValueError, KeyError) as e:
        raise DataError(f"{path}: unreadable chunk ({e}); delete it and run the sweep again") from None
    if meta.get("fingerprint") != fingerprint:
        raise DataError(
            f"{path}: this chunk belongs to another sweep; delete it or use another output folder"
        )
    return estimate, replicates


def merge(out: Path, config: SweepConfig, evaluator: Evaluator, provenance: dict[str, Any]) -> tuple:
    """Merge the chunks (in index order) and write every table of the output folder."""
    from glu.experiments.corpus import chunk_ranges

    cols = evaluator.columns
    K, B = len(cols), evaluator.settings.bootstrap
    frames = []
    for i, c in enumerate(config.conditions):
        total = np.zeros((B + 1, K))
        for k, _ in chunk_ranges(config.per_condition, config.chunk_size):
            est, reps = read_chunk(chunk_path(out, i, k), provenance["fingerprint"])
            total[0] += est
            total[1:] += reps.astype(np.float64)
        f = pd.DataFrame(total, columns=[f"s{j}" for j in range(K)])
        f.insert(0, "replicate", np.arange(B + 1))
        f.insert(0, "posterior", c.posterior)
        f.insert(0, "viewpoint", c.viewpoint)
        f.insert(0, "noise", c.noise)
        frames.append(f)
    sums = pd.concat(frames, ignore_index=True)
    # every grouping keeps the posterior: pooling two ways of reading the HMMs would mean nothing
    groups = {
        ("noise", "viewpoint"): {},
        ("noise",): {"viewpoint": "all"},
        ("viewpoint",): {"noise": np.nan},
        (): {"noise": np.nan, "viewpoint": "all"},
    }
    order = ["noise", "viewpoint", "posterior"]

    def pooled(fn, by_all=True):
        parts = []
        for by, fill in groups.items():
            if not by_all and by not in (("noise", "viewpoint"), ()):
                continue
            part = fn(sums, cols, [*by, "posterior"]).assign(**fill)
            parts.append(part[order + [c for c in part.columns if c not in order]])
        return pd.concat(parts, ignore_index=True)

    table = pooled(metrics)
    diffs = pooled(paired_differences, by_all=False)
    rel = pooled(reliability, by_all=False)
    params = provenance["settings"]
    source = provenance["data_source"]
    for df, name in ((table, EXPERIMENT), (diffs, "corpus_differences"), (rel, "corpus_reliability")):
        tidy(df, name, source, **params)
    summary = summarize(table, diffs, provenance)
    _write_parquet(out / "sums.parquet", sums)
    _write_parquet(out / "results.parquet", table)
    _write_parquet(out / "differences.parquet", diffs)
    _write_parquet(out / "reliability.parquet", rel)
    atomic_write_json(out / "summary.json", summary)
    head = pd.DataFrame(summary["overall"])
    atomic_write_text(out / "summary.csv", head.to_csv(index=False, float_format="%.6g", lineterminator="\n"))
    return table, diffs, rel, summary


def _write_parquet(path: Path, df: pd.DataFrame) -> None:
    with atomic_path(path, suffix=".parquet") as tmp:
        df.to_parquet(tmp, index=False)


def summarize(table: pd.DataFrame, diffs: pd.DataFrame, provenance: dict[str, Any]) -> dict[str, Any]:
    """The tidy summary: overall metrics at the full gesture, and per posterior, target and metric the best
    strategy (all strategies tied with it; the reference ``true_action`` left out) and those it beats with
    95 % confidence."""
    full = max(table["fraction"].dropna()) if table["fraction"].notna().any() else np.nan
    overall = table[(table.viewpoint == "all") & table.noise.isna() & (table.fraction == full)]
    rows = [
        {
            k: (None if isinstance(v, float) and not np.isfinite(v) else v)
            for k, v in r.items()
            if k not in ("noise", "viewpoint")
        }
        for r in overall.to_dict("records")
    ]
    best = []
    d_all = diffs[(diffs.viewpoint == "all") & diffs.noise.isna() & (diffs.fraction == full)]
    for (posterior, target, metric), g in overall.groupby(["posterior", "target", "metric"], sort=False):
        up = HIGHER_IS_BETTER.get(metric, True)
        g = g[~g.strategy.isin(REFERENCES)]  # the true action is a ceiling, not a strategy
        if g.empty:
            continue
        top = g.sort_values("estimate", ascending=not up).iloc[0]
        tied = sorted(g.strategy[np.isclose(g.estimate, top.estimate, rtol=0, atol=1e-12)])
        d = d_all[(d_all.posterior == posterior) & (d_all.target == target) & (d_all.metric == metric)]
        beats = []
        for p in d.itertuples():
            if top.strategy not in (p.strategy, p.baseline):
                continue
            other, sign = (p.baseline, 1) if p.strategy == top.strategy else (p.strategy, -1)
            if other in REFERENCES:
                continue
            lo, hi = sorted((sign * p.ci_low, sign * p.ci_high))
            if (lo > 0) if up else (hi < 0):
                beats.append(other)
        best.append(
            {
                "posterior": posterior,
                "target": target,
                "metric": metric,
                "fraction": full,
                "best": tied,
                "estimate": float(top.estimate),
                "ci_low": float(top.ci_low),
                "ci_high": float(top.ci_high),
                "significantly_better_than": sorted(beats),
            }
        )
    return {
        "experiment": EXPERIMENT,
        "data_source": provenance["data_source"],
        "fingerprint": provenance["fingerprint"],
        "episodes": provenance["episodes"],
        "conditions": provenance["conditions"],
        "parameters": provenance["settings"],
        "files": list(FILES),
        "overall": rows,
        "best": best,
    }
