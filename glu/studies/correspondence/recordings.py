"""The Rerun recording of one gesture seen from two viewpoints, raw and aligned by invariant features."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from glu.recording import log_path, log_scene, log_series, log_skeleton, new_recording, rerun

FEATURE_RGB = {"raw": (150, 150, 150), "aligned": (221, 132, 82)}


def two_views_blueprint(n_views: int):
    """Viewer layout: one column per view — the person seen by the camera, the raw and aligned features
    in 3-D, and p_HMM over time from each recogniser."""
    import rerun.blueprint as rrb

    cols = []
    for i in range(1, n_views + 1):
        cols.append(
            rrb.Vertical(
                rrb.Spatial3DView(origin=f"/view{i}/camera", name=f"view {i}: seen by the camera"),
                rrb.Spatial3DView(
                    origin=f"/view{i}/features", name=f"view {i}: raw (grey) and aligned features"
                ),
                rrb.TimeSeriesView(
                    origin=f"/view{i}/p_hmm/raw",
                    name=f"view {i}: p_HMM, raw features",
                    axis_y=rrb.ScalarAxis(range=(0.0, 1.0)),
                ),
                rrb.TimeSeriesView(
                    origin=f"/view{i}/p_hmm/aligned",
                    name=f"view {i}: p_HMM, aligned features",
                    axis_y=rrb.ScalarAxis(range=(0.0, 1.0)),
                ),
                row_shares=[2, 2, 1, 1],
            )
        )
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.TextDocumentView(origin="/scene", name="scene"), rrb.Horizontal(*cols), row_shares=[1, 6]
        ),
        rrb.TimePanel(state="collapsed"),
        collapse_panels=True,
    )


def write_two_views(runs: Sequence, path: str | os.PathLike, recording_id: str, scene: str = "") -> Path:
    """Write one gesture seen from several viewpoints, raw and aligned, with each recogniser's posterior.

    ``runs``: :class:`glu.studies.correspondence.two_views.ViewRun` objects, one per view. Layout (view ``i``
    = 1, 2, …)::

        /scene                        markdown: what is shown (static)
        /view<i>/camera/joints|bones  the person as the camera sees it (metres)
        /view<i>/features/raw         the hand features as seen (path and current point)
        /view<i>/features/aligned     the recogniser's invariant features of the same frames
        /view<i>/p_hmm/raw/<A>        p_HMM(A | G_1^t) of the raw-feature recogniser
        /view<i>/p_hmm/aligned/<A>    p_HMM(A | G_1^t) of the invariant recogniser

    Every 3-D entity is in glu's axes (x right, y up, z back: ``ViewCoordinates.RUB``); timelines
    ``frame`` (1-based) and ``time`` (s).
    """
    from glu.gestures.features import OPENNI_JOINTS

    rr = rerun()
    rec = new_recording(path, recording_id, two_views_blueprint(len(runs)))
    try:
        lines = [scene or "# One gesture, two viewpoints", ""]
        for i, run in enumerate(runs, start=1):
            lines.append(
                f"* view {i}: {run.label} — {run.view.describe()}; final p_HMM raw "
                + ", ".join(f"{a} {p:.2f}" for a, p in zip(run.actions, run.p_raw[-1], strict=True))
                + "; aligned "
                + ", ".join(f"{a} {p:.2f}" for a, p in zip(run.actions, run.p_aligned[-1], strict=True))
            )
        log_scene(rec, "\n".join(lines))
        for i, run in enumerate(runs, start=1):
            rec.log(f"view{i}", rr.ViewCoordinates.RUB, static=True)
            frames = np.arange(1, len(run.seconds) + 1)
            log_skeleton(rec, f"view{i}/camera", run.skeleton, OPENNI_JOINTS, run.seconds)
            log_path(rec, f"view{i}/features/raw", run.raw, run.seconds, FEATURE_RGB["raw"])
            log_path(rec, f"view{i}/features/aligned", run.aligned, run.seconds, FEATURE_RGB["aligned"])
            log_series(rec, f"view{i}/p_hmm/raw", run.p_raw, run.actions, frames, run.seconds)
            log_series(rec, f"view{i}/p_hmm/aligned", run.p_aligned, run.actions, frames, run.seconds)
    finally:
        rec.disconnect()
    return Path(path)
