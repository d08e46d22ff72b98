"""The README's bullet on effect anticipation (TCDS Fig. 5, notebook 08), written from its tables."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

Tables = Mapping[str, tuple[pd.DataFrame, dict[str, Any]]]

TEMPLATE = """\
* **Effect anticipation (TCDS Fig. 5).** With the original HMMs, on the originals' schedule (an update every \
{step:.0f} frames, the last at the last multiple of {step:.0f}), {anticipation_within:.0f} of \
{anticipation_n:.0f} values of the published curves and bars are reproduced within the figure's resolution \
(max |difference| {anticipation_max:.1e}), and both captions are the paper's: "{sphere_caption}", \
"{box_caption}"."""
"""The bullet, with ``{name:format}`` slots filled by :func:`values`."""

REQUIRED: tuple[str, ...] = (
    "tcds_anticipation_sphere_published",
    "tcds_anticipation_box_published",
    "tcds_anticipation_sphere_original_predictions",
)
"""The result tables the bullet is written from."""


def values(tables: Tables) -> dict[str, Any]:
    """Every slot of :data:`TEMPLATE`, from the run's tables (name → (rows, meta))."""
    v: dict[str, Any] = {}
    within, n, worst_diff = 0, 0, 0.0
    for case in ("sphere", "box"):
        df, meta = tables[f"tcds_anticipation_{case}_published"]
        within, n = within + int(df["within"].sum()), n + len(df)
        worst_diff = max(worst_diff, float(df["difference"].abs().max()))
        same = meta["parameters"]["same_caption"]
        v[f"{case}_caption"] = meta["parameters"]["caption"] if same else "(not the paper's caption)"
    v.update(anticipation_within=within, anticipation_n=n, anticipation_max=worst_diff)
    v["step"] = tables["tcds_anticipation_sphere_original_predictions"][1]["parameters"]["step"]
    return v
