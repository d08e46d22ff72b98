"""Rerun recordings (``.rrd``) of experiments that unfold over time: gestures and beliefs, frame by frame.

One function per concept (the trajectory, the HMM series, the posterior bars, the scene text), a blueprint
built by a function, explicit ``frame`` and ``time`` timelines, whole series sent with ``send_columns``.
Each file is written headless through its own :class:`rerun.RecordingStream` with an explicit recording id
and closed with ``disconnect()`` so the footer is written; open it with ``rerun FILE.rrd``.

Layout of a recording written by :func:`write_anticipation_recording`::

    /scene                     markdown: what is happening, the data source (static)
    /hand/position             the hand at frame t (Points3D)
    /hand/path                 the path so far (LineStrips3D, growing)
    /hmm/loglik_per_frame/<A>  (1/t) log L(G_1^t | A), one series per action model
    /hmm/p_hmm/<A>             p_HMM(A | G_1^t)
    /fusion/ObjVel/<value>     p_comb(ObjVel = value | Shape, Size, G_1^t), one labelled bar per value,
                               updated every few frames (the view's legend names slow, medium, fast)
    /fusion/Action/<value>     p_comb(Action = value | …), one bar per action
    /description               the best verbal description so far (TextLog), if given

:func:`write_two_views` records one gesture seen from several viewpoints, raw and aligned by invariant
features, with each recogniser's posterior over time; :func:`write_learning` an online learner of gestures,
episode by episode (their layouts are in their docstrings).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from glu.experiments.anticipation import AnticipationRun
from glu.machine import is_live, viewer_class

ACTION_RGB = {
    "grasp": (76, 114, 176),
    "tap": (221, 132, 82),
    "touch": (85, 168, 104),
    "push": (129, 114, 179),
}
VALUE_RGB = {"slow": (141, 160, 203), "medium": (252, 141, 98), "fast": (102, 194, 165)}
"""Colours of the values in the bar charts (the figures' colours)."""


def _rr():
    import rerun as rr

    return rr


def new_recording(path: str | os.PathLike, recording_id: str, blueprint=None, application_id: str = "glu"):
    """Open a RecordingStream that writes to ``path`` (log time off, so same data → same content)."""
    rr = _rr()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # no time-based flushing: the chunks of a file depend on its data only, not on how fast it was logged
    rec = rr.RecordingStream(
        application_id,
        recording_id=recording_id,
        send_properties=False,
        batcher_config=rr.ChunkBatcherConfig.NEVER(),
    )
    rec.set_log_time_enabled(False)
    rec.save(str(path), default_blueprint=blueprint)
    return rec


def anticipation_blueprint(actions: Sequence[str]):
    """Viewer layout: the hand in 3-D and the scene text on the left; HMM series and fused bars on the
    right."""
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
                    rrb.BarChartView(origin="/fusion/ObjVel", name="p_comb(ObjVel)"),
                    rrb.BarChartView(origin="/fusion/Action", name="p_comb(Action)"),
                ),
            ),
            column_shares=[1, 1],
        ),
        rrb.TimePanel(state="collapsed"),
        collapse_panels=True,
    )


def log_scene(rec, markdown: str) -> None:
    """The static text panel describing the scene."""
    rr = _rr()
    rec.log("scene", rr.TextDocument(markdown, media_type="text/markdown"), static=True)


def log_trajectory(rec, xyz: np.ndarray, frames: np.ndarray, seconds: np.ndarray) -> None:
    """The hand position and its growing path, one row per frame (xyz: shape (n_frames, 3))."""
    rr = _rr()
    xyz = np.asarray(xyz, dtype=np.float32)
    for k, (f, t) in enumerate(zip(frames, seconds, strict=True)):
        rec.set_time("frame", sequence=int(f))
        rec.set_time("time", duration=float(t))
        rec.log("hand/position", rr.Points3D(xyz[k : k + 1], radii=0.02, colors=(255, 200, 0)))
        rec.log("hand/path", rr.LineStrips3D([xyz[: k + 1]], radii=0.004, colors=(200, 200, 200)))


def log_series(
    rec, entity: str, values: np.ndarray, names: Sequence[str], frames: np.ndarray, seconds: np.ndarray
) -> None:
    """One time series per column of ``values`` (shape (n_frames, n_series)) under ``entity/<name>``."""
    rr = _rr()
    values = np.asarray(values, dtype=float)
    for j, name in enumerate(names):
        color = ACTION_RGB.get(name, (120, 120, 120))
        rec.log(f"{entity}/{name}", rr.SeriesLines(names=name, colors=color), static=True)
        finite = np.isfinite(values[:, j])
        rec.send_columns(
            f"{entity}/{name}",
            indexes=[
                rr.TimeColumn("frame", sequence=np.asarray(frames)[finite].astype(np.int64)),
                rr.TimeColumn("time", duration=np.asarray(seconds)[finite].astype(float)),
            ],
            columns=rr.Scalars.columns(scalars=values[finite, j]),
        )


def log_bars(
    rec, entity: str, probs: np.ndarray, values: Sequence[str], frames: np.ndarray, seconds: np.ndarray
) -> None:
    """Labelled bars that change over time: ``probs`` shape (n_updates, n_values), one row per update frame.

    Rerun's bar charts have no category labels, so each value is its own entity ``entity/<value>`` with
    one bar at its position: the bar-chart view then names each bar in its legend.
    """
    rr = _rr()
    probs = np.asarray(probs, dtype=float)
    for j, value in enumerate(values):
        color = VALUE_RGB.get(value) or ACTION_RGB.get(value) or (120, 120, 120)
        for p, f, t in zip(probs[:, j], frames, seconds, strict=True):
            rec.set_time("frame", sequence=int(f))
            rec.set_time("time", duration=float(t))
            rec.log(f"{entity}/{value}", rr.BarChart([p], abscissa=[float(j)], color=color))


def log_texts(rec, entity: str, texts: Sequence[str], frames: np.ndarray, seconds: np.ndarray) -> None:
    """Text lines at given frames (e.g. the current best verbal description)."""
    rr = _rr()
    for text, f, t in zip(texts, frames, seconds, strict=True):
        rec.set_time("frame", sequence=int(f))
        rec.set_time("time", duration=float(t))
        rec.log(entity, rr.TextLog(text, level=rr.TextLogLevel.INFO))


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
    descriptions : the best verbal description at each update frame, or at the last ones only (optional)
    values : node → its value names, in the column order of ``fused[node]`` (default: ``0, 1, …``)
    """
    log_scene(rec, scene)
    log_trajectory(rec, xyz, frames, seconds)
    log_series(rec, "hmm/loglik_per_frame", loglik_per_frame, actions, frames, seconds)
    log_series(rec, "hmm/p_hmm", p_hmm, actions, frames, seconds)
    upd_seconds = np.interp(update_frames, frames, seconds)
    for node, probs in fused.items():
        names = (values or {}).get(node) or [str(i) for i in range(np.shape(probs)[1])]
        log_bars(rec, f"fusion/{node}", probs, names, update_frames, upd_seconds)
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
    scene = run.scene() + (f"\n\n<small>{note}</small>" if note else "")
    return dict(
        xyz=run.xyz,
        seconds=run.seconds,
        frames=run.frames,
        actions=run.actions,
        loglik_per_frame=run.loglik_per_frame,
        p_hmm=run.p_hmm,
        update_frames=run.update_frames,
        fused=run.fused,
        scene=scene,
        descriptions=run.descriptions or None,
        values=run.values,
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
    rr = _rr()
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
    """Write an effect-anticipation run (:func:`glu.experiments.anticipation.effect_anticipation`) as a
    recording.

    ``note`` (e.g. the notebook's data source and non-default parameters) ends the scene text.
    """
    return write_anticipation_recording(path, recording_id, **_run_fields(run, note))


# ------------------------------------------------------------------ one gesture, two viewpoints

SKELETON_BONES: tuple[tuple[str, ...], ...] = (
    ("head", "neck", "torso"),
    ("left_hand", "left_elbow", "left_shoulder", "neck", "right_shoulder", "right_elbow", "right_hand"),
    ("left_foot", "left_knee", "left_hip", "torso", "right_hip", "right_knee", "right_foot"),
)
"""Chains of OpenNI joints drawn as the skeleton."""
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


def log_skeleton(rec, entity: str, skeleton: np.ndarray, joints: Sequence[str], seconds: np.ndarray) -> None:
    """A skeleton over time, shape (n_frames, n_joints, 3): its joints as points and bones as line strips."""
    rr = _rr()
    index = {j: k for k, j in enumerate(joints)}
    chains = [[index[j] for j in chain] for chain in SKELETON_BONES]
    for k, t in enumerate(seconds):
        rec.set_time("frame", sequence=k + 1)
        rec.set_time("time", duration=float(t))
        pts = np.asarray(skeleton[k], dtype=np.float32)
        rec.log(f"{entity}/joints", rr.Points3D(pts, radii=0.015, colors=(90, 90, 90)))
        rec.log(
            f"{entity}/bones", rr.LineStrips3D([pts[c] for c in chains], radii=0.006, colors=(120, 120, 120))
        )


def log_path(rec, entity: str, xyz: np.ndarray, seconds: np.ndarray, color: tuple[int, int, int]) -> None:
    """A 3-D path growing frame by frame (``xyz`` shape (n_frames, 3)), its current point marked."""
    rr = _rr()
    xyz = np.asarray(xyz, dtype=np.float32)
    for k, t in enumerate(seconds):
        rec.set_time("frame", sequence=k + 1)
        rec.set_time("time", duration=float(t))
        rec.log(f"{entity}/position", rr.Points3D(xyz[k : k + 1], radii=0.03, colors=color))
        rec.log(f"{entity}/path", rr.LineStrips3D([xyz[: k + 1]], radii=0.008, colors=color))


def write_two_views(runs: Sequence, path: str | os.PathLike, recording_id: str, scene: str = "") -> Path:
    """Write one gesture seen from several viewpoints, raw and aligned, with each recogniser's posterior.

    ``runs``: :class:`glu.experiments.two_views.ViewRun` objects, one per view. Layout (view ``i``
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

    rr = _rr()
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


# ------------------------------------------------------------------ learning gestures online


def learning_blueprint(actions: Sequence[str]):
    """Viewer layout: the models' mean trajectories and this episode's gesture in 3-D; the labels, their
    confidence and the held-out accuracy over the episodes."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial3DView(origin="/space", name="models' mean trajectories, this episode's gesture"),
                rrb.TextDocumentView(origin="/scene", name="scene"),
                row_shares=[5, 2],
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(
                    origin="/labels", name="label weight per action", axis_y=rrb.ScalarAxis(range=(0.0, 1.0))
                ),
                rrb.TimeSeriesView(
                    origin="/accuracy",
                    name="held-out accuracy so far",
                    axis_y=rrb.ScalarAxis(range=(0.0, 1.0)),
                ),
                rrb.TextLogView(origin="/decisions", name="episode by episode"),
            ),
            column_shares=[1, 1],
        ),
        rrb.TimePanel(state="collapsed"),
        collapse_panels=True,
    )


def log_episode_gestures(rec, features: Sequence[np.ndarray], true_actions: Sequence[str]) -> None:
    """Each episode's hand path (shape (T_i, 3)) at its step of the ``episode`` timeline, coloured by its
    true action."""
    rr = _rr()
    for i, (X, a) in enumerate(zip(features, true_actions, strict=True), start=1):
        rec.set_time("episode", sequence=i)
        xyz = np.asarray(X, dtype=np.float32)
        rec.log(
            "space/episode", rr.LineStrips3D([xyz], radii=0.006, colors=ACTION_RGB.get(a, (120, 120, 120)))
        )


def log_labels(rec, weights: np.ndarray, actions: Sequence[str], true_actions: Sequence[str]) -> None:
    """The label weight each episode gave each action (``weights`` shape (N, A)) as one series per action,
    and a line per episode: its true action, the label and its confidence."""
    rr = _rr()
    episodes = np.arange(1, len(weights) + 1)
    log_series_on(rec, "labels", weights, actions, episodes)
    for i, (w, a) in enumerate(zip(weights, true_actions, strict=True), start=1):
        rec.set_time("episode", sequence=i)
        text = "no label" if w.max() <= 0 else f"labelled {actions[int(np.argmax(w))]} ({w.max():.2f})"
        rec.log("decisions", rr.TextLog(f"episode {i}: {a}, {text}", level=rr.TextLogLevel.INFO))


def log_series_on(rec, entity: str, values: np.ndarray, names: Sequence[str], steps: np.ndarray) -> None:
    """One series per column of ``values`` (shape (n, k)) under ``entity/<name>`` on the ``episode``
    timeline."""
    rr = _rr()
    for j, name in enumerate(names):
        rec.log(
            f"{entity}/{name}",
            rr.SeriesLines(names=name, colors=ACTION_RGB.get(name, (90, 90, 90))),
            static=True,
        )
        rec.send_columns(
            f"{entity}/{name}",
            indexes=[rr.TimeColumn("episode", sequence=np.asarray(steps, dtype=np.int64))],
            columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=float)[:, j]),
        )


def log_model_means(rec, checkpoints: np.ndarray, means: np.ndarray, actions: Sequence[str]) -> None:
    """Each model's state means (``means`` shape (C, A, Q, D), NaN without a model) as a 3-D path, at each
    checkpoint of the ``episode`` timeline."""
    rr = _rr()
    for c, n in enumerate(checkpoints):
        rec.set_time("episode", sequence=int(n))
        for a, name in enumerate(actions):
            m = np.asarray(means[c, a], dtype=np.float32)
            if np.isnan(m).any():
                continue
            color = ACTION_RGB.get(name, (120, 120, 120))
            rec.log(f"space/models/{name}/path", rr.LineStrips3D([m], radii=0.012, colors=color))
            rec.log(f"space/models/{name}/states", rr.Points3D(m, radii=0.025, colors=color))


def write_learning(
    run: Any, features: Sequence[np.ndarray], path: str | os.PathLike, recording_id: str, scene: str
) -> Path:
    """Write one online learner's life (:class:`glu.experiments.online_learning.OnlineRun` of one learner,
    ``features`` its episodes' gestures) as a recording. Layout (timeline ``episode``)::

        /scene                     markdown: what is shown (static)
        /space/episode             this episode's hand path (3-D), coloured by its true action
        /space/models/<A>/path     model A's state means, a 3-D path, at each checkpoint
        /labels/<A>                the label weight this episode gave action A
        /accuracy/held-out         the held-out accuracy at each checkpoint
        /decisions                 a line per episode: true action, label, confidence
    """
    rr = _rr()
    actions = list(run.actions)
    true = [actions[a] for a in run.episode_actions]
    rec = new_recording(path, recording_id, learning_blueprint(actions))
    try:
        log_scene(rec, scene)
        rec.log("space", rr.ViewCoordinates.RUB, static=True)
        log_episode_gestures(rec, features, true)
        log_labels(rec, run.weights[:, 0], actions, true)
        log_series_on(rec, "accuracy", run.accuracy()[:, :1], ["held-out"], run.checkpoints)
        log_model_means(rec, run.checkpoints, run.means[:, 0], actions)
    finally:
        rec.disconnect()
    return Path(path)
