"""The Rerun recording of effect anticipation: the hand, the HMMs' scores, the fused beliefs, frame by frame.

Layout of a recording written by :func:`write_anticipation_recording`::

    /scene                     markdown: what is happening, the data source (static)
    /hand/position             the hand at frame t (Points3D)
    /hand/path                 the path so far (LineStrips3D, growing)
    /hmm/loglik_per_frame/<A>  (1/t) log L(G_1^t | A), one series per action model
    /hmm/p_hmm/<A>             p_HMM(A | G_1^t)
    /fusion/ObjVel/<value>     p_comb(ObjVel = value | Shape, Size, G_1^t), one named series per value,
                               a point at each update (every few frames), a line between them
    /fusion/Action/<value>     p_comb(Action = value | …), one series per action
    /description               the best verbal description so far (TextLog), if given
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from glu.machine import is_live, viewer_class
from glu.recording import log_scene, log_series, log_texts, log_trajectory, log_updates, new_recording, rerun
from glu.studies.anticipation.experiment import AnticipationRun


def anticipation_blueprint(actions: Sequence[str]):
    """Viewer layout: the hand in 3-D and the scene text on the left; the HMMs' series and the fused
    beliefs at each update on the right, every probability on the same 0–1 axis."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial3DView(origin="/hand", name="hand trajectory"),
                rrb.TextDocumentView(origin="/scene", name="scene"),
                rrb.TextLogView(origin="/description", name="description"),
                row_shares=[5, 4, 2],
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(origin="/hmm/loglik_per_frame", name="(1/t) log L(G | A)"),
                rrb.TimeSeriesView(
                    origin="/hmm/p_hmm", name="p_HMM(A | G)", axis_y=rrb.ScalarAxis(range=(0.0, 1.0))
                ),
                rrb.Horizontal(
                    rrb.TimeSeriesView(
                        origin="/fusion/ObjVel",
                        name="p_comb(ObjVel)",
                        axis_y=rrb.ScalarAxis(range=(0.0, 1.0)),
                    ),
                    rrb.TimeSeriesView(
                        origin="/fusion/Action",
                        name="p_comb(Action)",
                        axis_y=rrb.ScalarAxis(range=(0.0, 1.0)),
                    ),
                ),
            ),
            column_shares=[1, 1],
        ),
        rrb.TimePanel(state="collapsed"),
        collapse_panels=True,
    )


def log_anticipation(
    rec,
    xyz: np.ndarray,
    seconds: np.ndarray,
    frames: np.ndarray,
    actions: Sequence[str],
    loglik_per_frame: np.ndarray,
    p_hmm: np.ndarray,
    update_frames: np.ndarray,
    fused: Mapping[str, np.ndarray],
    scene: str,
    descriptions: Sequence[str] | None = None,
    values: Mapping[str, Sequence[str]] | None = None,
    note: str = "",
) -> None:
    """Log one effect-anticipation run into the stream ``rec`` (see the module docstring for the layout).

    Parameters
    ----------
    xyz, seconds, frames : hand positions (n_frames, 3), their times in s from the start, frame numbers
    actions : names of the HMM models, in the column order of ``loglik_per_frame`` and ``p_hmm``
    loglik_per_frame, p_hmm : arrays, shape (n_frames, n_actions)
    update_frames : frame numbers at which the fused posteriors were computed, shape (n_updates,)
    fused : node → array, shape (n_updates, n_values), e.g. {"ObjVel": …, "Action": …}
    scene : markdown for the scene panel
    note : plain text that ends the scene panel (the data, the run's non-default parameters)
    descriptions : the best verbal description at each update frame, or at the last ones only (optional)
    values : node → its value names, in the column order of ``fused[node]`` (default: ``0, 1, …``)
    """
    log_scene(rec, scene, note)
    log_trajectory(rec, xyz, frames, seconds)
    log_series(rec, "hmm/loglik_per_frame", loglik_per_frame, actions, frames, seconds)
    log_series(rec, "hmm/p_hmm", p_hmm, actions, frames, seconds)
    upd_seconds = np.interp(update_frames, frames, seconds)
    for node, probs in fused.items():
        names = (values or {}).get(node) or [str(i) for i in range(np.shape(probs)[1])]
        log_updates(rec, f"fusion/{node}", probs, names, update_frames, upd_seconds)
    if descriptions:  # at every update, or at the last ones only
        k = len(descriptions)
        log_texts(rec, "description", descriptions, update_frames[-k:], upd_seconds[-k:])


def write_anticipation_recording(path: str | os.PathLike, recording_id: str, **run: Any) -> Path:
    """Write one effect-anticipation run to an ``.rrd`` file; ``run`` as :func:`log_anticipation` takes it."""
    rec = new_recording(path, recording_id, anticipation_blueprint(run["actions"]))
    try:
        log_anticipation(rec, **run)
    finally:
        rec.disconnect()
    return Path(path)


def _run_fields(run: AnticipationRun, note: str) -> dict[str, Any]:
    names = "xyz seconds frames actions loglik_per_frame p_hmm update_frames fused values".split()
    return {k: getattr(run, k) for k in names} | dict(
        scene=run.scene(), descriptions=run.descriptions or None, note=note or run.data_source
    )


def show_anticipation(
    run: AnticipationRun, recording_id: str, note: str = "", live: bool | None = None
) -> Any:
    """The Rerun viewer inline in a live notebook, replaying the run; None when headless.

    Needs ``rerun-notebook`` (``pip install 'glu[lab]'``); without it, or headless (``glu reproduce``),
    nothing is shown and None is returned: the ``.rrd`` files are the artefact either way.
    """
    if not is_live(live):
        return None
    rr = rerun()
    Viewer = viewer_class()
    if Viewer is None:
        return None
    rec = rr.RecordingStream("glu", recording_id=recording_id, send_properties=False)
    rec.set_log_time_enabled(False)
    try:
        viewer = Viewer(
            recording=rec, width="auto", height=560, blueprint=anticipation_blueprint(run.actions)
        )
    except Exception:  # rerun-notebook or ipywidgets missing: the static artefact stays the .rrd file
        return None
    log_anticipation(rec, **_run_fields(run, note))
    return viewer


def write_anticipation(
    run: AnticipationRun, path: str | os.PathLike, recording_id: str, note: str = ""
) -> Path:
    """Write an effect-anticipation run (:func:`glu.studies.anticipation.experiment.effect_anticipation`) as a
    recording.

    ``note`` (e.g. the notebook's data source and non-default parameters; default: the run's data source)
    ends the scene text.
    """
    return write_anticipation_recording(path, recording_id, **_run_fields(run, note))
