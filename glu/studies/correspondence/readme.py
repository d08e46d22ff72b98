"""The README's bullets on the correspondence problem (notebooks 08 and 10), written from their tables.

The sentences come from the functions that write the notebook's interpretation
(:mod:`glu.studies.correspondence.text`), so the README and the notebook cannot say different things.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

from glu.errors import DataError
from glu.stats import LEVEL
from glu.studies.correspondence.text import nested_sentences, study_sentences

Tables = Mapping[str, tuple[pd.DataFrame, dict[str, Any]]]

TEMPLATE = """\
* **The correspondence problem, on the real data** (`10_correspondence`). The seated hand works elsewhere in \
the torso frame: mean height y of the two seated taps {seated_y_lo:.2f} and {seated_y_hi:.2f}, at most \
{standing_y_max:.2f} for every standing repetition; depth z {seated_z_lo:.2f} and {seated_z_hi:.2f}, at \
least {standing_z_min:.2f} standing; across, x {seated_x_lo:.2f} and {seated_x_hi:.2f} (left of the \
torso), at least {standing_x_min:.2f} (right of it) for every standing repetition.
  * On the {loso_n:.0f} real segments of the three standing recordings (one person), leave-one-segment-out \
on raw features gives {raw_loso_span} over {raw_loso_runs:.0f} covariance priors and seeds; with one segment \
worth {segment_points:.0f} points, single accuracies are fragile.
{nested_text}
  * Effect anticipation with glu's centred HMMs (`08_tcds_figures`) ends as the originals' does: the sphere \
will move (p(ObjVel = slow) {glu_sphere_slow:.3f}), the box will not ({glu_box_slow:.3f}).
* **Invariant features and the body frame, on synthetic people** (`10_correspondence`; HMMs trained on \
standard people facing the camera, tested on other people, {study_seeds:.0f} seeds, {ci_percent:.0f} % \
two-level intervals over the seeds and the test gestures from {study_bootstrap:,.0f} replicates; the \
invariances' paired effects adjusted for their number by Benjamini–Hochberg; notebook 10 adds a mirror \
image, seated people, sensor noise and all at once).
{study_text}"""
"""The bullets, with ``{name:format}`` slots filled by :func:`values`."""

REQUIRED: tuple[str, ...] = (
    "posture_offsets",
    "tcds_anticipation_sphere_glu_predictions",
    "tcds_anticipation_box_glu_predictions",
    "correspondence_summary",
    "correspondence_invariance_effects",
    "correspondence_nested_cv",
    "correspondence_candidates",
    "seated_typicality",
)
"""The result tables the bullets are written from."""


def values(tables: Tables) -> dict[str, Any]:
    """Every slot of :data:`TEMPLATE`, from the run's tables (name → (rows, meta))."""
    v = _loso(tables)
    off = tables["posture_offsets"][0]
    sat, stand = off[off["posture"] == "seated"], off[off["posture"] == "standing"]
    v.update(
        seated_y_lo=sat["y"].min(),
        seated_y_hi=sat["y"].max(),
        standing_y_max=stand["y"].max(),
        seated_z_lo=sat["z"].min(),
        seated_z_hi=sat["z"].max(),
        standing_z_min=stand["z"].min(),
        seated_x_lo=sat["x"].min(),
        seated_x_hi=sat["x"].max(),
        standing_x_min=stand["x"].min(),
    )
    v["nested_text"] = nested_sentences(
        tables["correspondence_nested_cv"][0],
        tables["seated_typicality"][0],
        tables["correspondence_candidates"][0],
        brief=True,
    )
    for case in ("sphere", "box"):
        pred = tables[f"tcds_anticipation_{case}_glu_predictions"][0]
        last = pred[(pred["node"] == "ObjVel") & (pred["frame"] == pred["frame"].max())]
        v[f"glu_{case}_slow"] = last.set_index("value")["p"]["slow"]
    study, meta = tables["correspondence_summary"]
    v["study_seeds"] = len(meta["parameters"]["seeds"])
    v["study_bootstrap"] = _replicates(meta)
    v["ci_percent"] = 100 * LEVEL
    v["study_text"] = study_sentences(study, tables["correspondence_invariance_effects"][0], brief=True)
    return v


def _loso(tables: Tables) -> dict[str, Any]:
    """The real segments' leave-one-segment-out on raw features, over covariance priors and seeds."""
    cands = tables["correspondence_candidates"][0]
    raw = cands[cands["features"] == "raw"]
    if raw.empty:
        raise DataError("the summary's correspondence_candidates has no raw-feature rows")
    n = int(tables["correspondence_nested_cv"][0]["testable"].max())
    lo, hi = f"{raw['loso_accuracy'].min():.2f}", f"{raw['loso_accuracy'].max():.2f}"
    return {
        "loso_n": n,
        "segment_points": 100 / n,
        "raw_loso_span": lo if lo == hi else f"{lo}–{hi}",
        "raw_loso_runs": len(raw),
    }


def _replicates(meta: dict[str, Any]) -> int:
    """The bootstrap replicates a summary's intervals were drawn with (its ``interval`` stamp)."""
    import re

    m = re.search(r"\((\d+) replicates\)", str(meta.get("parameters", {}).get("interval", "")))
    if m is None:
        raise DataError("the summary's correspondence_summary does not say how many replicates it drew")
    return int(m.group(1))
