"""The slots of the README's results section that the two studies fill: the corpus evaluation (notebook 11)
and the correspondence problem (notebooks 08 and 10), read from ``results/summary.json``.

The sentences come from the same functions that write the notebooks' interpretation
(:mod:`glu.experiments.findings`, :mod:`glu.experiments.correspondence_text`), so the README and the
notebooks cannot say different things.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

from glu.errors import DataError
from glu.experiments import findings as fd
from glu.experiments.correspondence_text import nested_sentences, study_sentences
from glu.experiments.intervals import LEVEL


def table(summary: Mapping[str, Any], name: str) -> tuple[pd.DataFrame, dict[str, Any]]:
    """A table of the summary: its rows as a frame, and its meta."""
    t = summary["tables"][name]
    return pd.DataFrame(t["rows"]), t["meta"]


def _bullets(sentences: list[str], indent: str = "  ") -> str:
    return "\n".join(f"{indent}* {s}" for s in sentences)


def loso_values(summary: Mapping[str, Any]) -> dict[str, Any]:
    """The real segments' leave-one-segment-out on raw features, over covariance priors and seeds."""
    cands = table(summary, "correspondence_candidates")[0]
    raw = cands[cands["features"] == "raw"]
    if raw.empty:
        raise DataError("the summary's correspondence_candidates has no raw-feature rows")
    n = int(table(summary, "correspondence_nested_cv")[0]["testable"].max())
    lo, hi = f"{raw['loso_accuracy'].min():.2f}", f"{raw['loso_accuracy'].max():.2f}"
    return {
        "loso_n": n,
        "segment_points": 100 / n,
        "raw_loso_span": lo if lo == hi else f"{lo}–{hi}",
        "raw_loso_runs": len(raw),
    }


def correspondence_values(summary: Mapping[str, Any]) -> dict[str, Any]:
    """The slots of the two correspondence bullets (notebooks 08 and 10)."""
    v: dict[str, Any] = {}
    off = table(summary, "posture_offsets")[0]
    sat, stand = off[off["posture"] == "seated"], off[off["posture"] == "standing"]
    v.update(
        seated_y_lo=sat["y"].min(),
        seated_y_hi=sat["y"].max(),
        standing_y_max=stand["y"].max(),
        seated_z_lo=sat["z"].min(),
        seated_z_hi=sat["z"].max(),
        standing_z_min=stand["z"].min(),
    )
    v["nested_text"] = _bullets(
        nested_sentences(
            table(summary, "correspondence_nested_cv")[0],
            table(summary, "seated_typicality")[0],
            table(summary, "correspondence_candidates")[0],
        )
    )
    for case in ("sphere", "box"):
        pred = table(summary, f"tcds_anticipation_{case}_glu_predictions")[0]
        last = pred[(pred["node"] == "ObjVel") & (pred["frame"] == pred["frame"].max())]
        v[f"glu_{case}_slow"] = last.set_index("value")["p"]["slow"]
    study, meta = table(summary, "correspondence_summary")
    v["study_seeds"] = len(meta["parameters"]["seeds"])
    v["study_text"] = _bullets(study_sentences(study, table(summary, "correspondence_invariance_effects")[0]))
    return v


def corpus_values(summary: Mapping[str, Any]) -> dict[str, Any]:
    """The slots of the corpus bullet, from the tables of notebook 11."""
    metrics, meta = table(summary, "corpus_metrics")
    params = meta["parameters"]
    grid = params["grid"]
    verdicts = table(summary, "corpus_findings")[0]
    cells = verdicts.drop_duplicates(list(fd.DESIGN))
    learned = [f"{n:,}" for n in grid["learn_experiments"]] if "learned" in grid["inference_network"] else []
    v: dict[str, Any] = {
        "corpus_episodes": meta["episodes"],
        "corpus_seeds": params["recognizer_seeds"],
        "ci_percent": 100 * LEVEL,
        "corpus_learned": " or ".join(learned) or "no",
        "corpus_cells": len(cells),
        "reference_cell": fd.cell_label(fd.REFERENCE_CELL),
        "findings_text": _bullets(fd.finding_sentences(verdicts, brief=True), "    "),
        "network_text": _bullets(fd.network_alone_sentences(metrics)),
    }
    segments = table(summary, "p_hmm_real_calibration")[0]
    v["p_hmm_text"] = _bullets(
        fd.p_hmm_sentences(
            metrics, table(summary, "corpus_calibration")[0], segments if len(segments) else None
        )
    )
    v["seed_text"] = fd.seed_sentence(fd.seed_spread(table(summary, "corpus_seeds")[0]))
    return v
