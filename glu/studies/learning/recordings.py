"""The Rerun recording of an online learner of gestures, episode by episode."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from glu.recording import ACTION_RGB, log_scene, log_series_on, new_recording, rerun


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
    rr = rerun()
    for i, (X, a) in enumerate(zip(features, true_actions, strict=True), start=1):
        rec.set_time("episode", sequence=i)
        xyz = np.asarray(X, dtype=np.float32)
        rec.log(
            "space/episode", rr.LineStrips3D([xyz], radii=0.006, colors=ACTION_RGB.get(a, (120, 120, 120)))
        )


def log_labels(rec, weights: np.ndarray, actions: Sequence[str], true_actions: Sequence[str]) -> None:
    """The label weight each episode gave each action (``weights`` shape (N, A)) as one series per action,
    and a line per episode: its true action, the label and its confidence."""
    rr = rerun()
    episodes = np.arange(1, len(weights) + 1)
    log_series_on(rec, "labels", weights, actions, episodes)
    for i, (w, a) in enumerate(zip(weights, true_actions, strict=True), start=1):
        rec.set_time("episode", sequence=i)
        text = "no label" if w.max() <= 0 else f"labelled {actions[int(np.argmax(w))]} ({w.max():.2f})"
        rec.log("decisions", rr.TextLog(f"episode {i}: {a}, {text}", level=rr.TextLogLevel.INFO))


def log_model_means(rec, checkpoints: np.ndarray, means: np.ndarray, actions: Sequence[str]) -> None:
    """Each model's state means (``means`` shape (C, A, Q, D), NaN without a model) as a 3-D path, at each
    checkpoint of the ``episode`` timeline."""
    rr = rerun()
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
    run: Any,
    features: Sequence[np.ndarray],
    path: str | os.PathLike,
    recording_id: str,
    scene: str,
    note: str = "",
) -> Path:
    """Write one online learner's life (:class:`glu.studies.learning.online.OnlineRun` of one learner,
    ``features`` its N episodes' gestures, each of shape (T_i, 3), in the run's order) as a recording;
    ``note`` (plain text: the data, the run's parameters) ends the scene panel. Layout (timeline
    ``episode``)::

        /scene                     markdown: what is shown (static)
        /space/episode             this episode's hand path (3-D), coloured by its true action
        /space/models/<A>/path     model A's state means, a 3-D path, at each checkpoint
        /labels/<A>                the label weight this episode gave action A
        /accuracy/held-out         the held-out accuracy at each checkpoint
        /decisions                 a line per episode: true action, label, confidence
    """
    rr = rerun()
    actions = list(run.actions)
    true = [actions[a] for a in run.episode_actions]
    rec = new_recording(path, recording_id, learning_blueprint(actions))
    try:
        log_scene(rec, scene, note)
        rec.log("space", rr.ViewCoordinates.RUB, static=True)
        log_episode_gestures(rec, features, true)
        log_labels(rec, run.weights[:, 0], actions, true)
        log_series_on(rec, "accuracy", run.accuracy()[:, :1], ["held-out"], run.checkpoints)
        log_model_means(rec, run.checkpoints, run.means[:, 0], actions)
    finally:
        rec.disconnect()
    return Path(path)
