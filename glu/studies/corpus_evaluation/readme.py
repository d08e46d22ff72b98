"""The README's bullet on the corpus evaluation (notebook 11), written from its tables.

The sentences come from the functions that write the notebook's interpretation
(:mod:`glu.studies.corpus_evaluation.findings`, :mod:`glu.studies.corpus_evaluation.conditions`), so the
README and the notebook cannot say different things. The bullet leads with the front view, where the
recogniser works, and then says where the conclusion changes.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

from glu.stats import LEVEL
from glu.studies.corpus_evaluation import conditions as cd
from glu.studies.corpus_evaluation import findings as fd

Tables = Mapping[str, tuple[pd.DataFrame, dict[str, Any]]]

TEMPLATE = """\
* **Every fusion strategy on a simulated corpus** (`11_corpus_evaluation`: {corpus_episodes:,.0f} episodes \
over {corpus_seeds:.0f} recogniser seeds, each with its own recognisers, learned networks and episodes; \
{ci_percent:.0f} % two-level intervals from {corpus_bootstrap:,.0f} bootstrap replicates; every family of \
verdicts adjusted for its size by Benjamini–Hochberg, and each verdict below is the adjusted one). \
{lead_text}
  * The effects and words are drawn from a network and the gestures from the generator the HMMs are trained \
on, so the design crosses the ways the robot's models can be wrong — actions drawn uniformly or from the \
network's prior; the robot's network the generating one or learned from {corpus_learned} simulated \
experiments; p_HMM read from the likelihoods, per frame, or calibrated on clean or on test-like held-out \
gestures; the recogniser's features raw, invariant or in the body frame — and breaks the simulator's own \
assumptions on purpose: effects that depend on the gesture as well as the action (a fast tap sends the \
object further, the slowest taps fail), and a skeleton tracker that loses the far shoulder side-on \
(`docs/corpus-evaluation.md`). Every verdict is computed per viewpoint and per noise level as well as pooled.
{viewpoint_text}
  * {validation_text}
  * {world_text}
  * Notebook 11 follows each earlier finding of this study (the product rule against the gesture alone, \
Jeffrey's rule against virtual evidence, a hard decision and the network alone, early and at the full \
gesture) through the {corpus_cells:.0f} cells of the robot's models (actions × network × p_HMM), every \
viewpoint, feature set and noise level, with the p_HMM readings' calibration and the spread over seeds."""
"""The bullet, with ``{name:format}`` slots filled by :func:`values`."""

REQUIRED: tuple[str, ...] = (
    "corpus_metrics",
    "corpus_findings",
    "corpus_calibration",
)
"""The result tables the bullet is written from."""


def values(tables: Tables) -> dict[str, Any]:
    """Every slot of :data:`TEMPLATE`, from the run's tables (name → (rows, meta))."""
    metrics, meta = tables["corpus_metrics"]
    params = meta["parameters"]
    grid = params["grid"]
    verdicts = tables["corpus_findings"][0]
    calibration = tables["corpus_calibration"][0]
    cells = verdicts.drop_duplicates(list(fd.CELL))
    learned = [f"{n:,}" for n in grid["learn_experiments"]] if "learned" in grid["inference_network"] else []
    best = cd.best_invariant(calibration)
    features = list(dict.fromkeys(["raw", *([best] if best else []), *grid.get("features", ["raw"])]))
    v: dict[str, Any] = {
        "corpus_episodes": meta["episodes"],
        "corpus_seeds": params["recognizer_seeds"],
        "corpus_bootstrap": params["evaluation"]["bootstrap"],
        "ci_percent": 100 * LEVEL,
        "corpus_learned": " or ".join(learned) or "no",
        "corpus_cells": len(cells),
        "lead_text": cd.lead_sentence(metrics, verdicts, best, grid.get("features", ())),
        "viewpoint_text": cd.viewpoint_sentences(metrics, features),
        "validation_text": cd.validation_sentence(calibration),
        "world_text": cd.gesture_world_sentence(metrics),
    }
    return v
