"""One action, two viewpoints: the same synthetic gesture seen from each view, through a raw and an
invariant recogniser, frame by frame (for :func:`glu.studies.correspondence.recordings.write_two_views` and
notebook 10, whose recording is :func:`one_tap_two_views`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from glu.gestures.invariants import ALL
from glu.gestures.recognizer import Recognizer
from glu.gestures.synthetic import SYNTHETIC_POLICY, View, synthesize_gesture
from glu.gestures.trajectories import repair
from glu.hmm import TrainingConfig
from glu.studies.correspondence.experiment import HUMAN_NOISE, train_for
from glu.tidy import tidy


@dataclass
class ViewRun:
    """One gesture seen from one viewpoint, through a raw and an invariant recogniser.

    Attributes
    ----------
    label : e.g. ``"yaw 0°"``
    view : how it was seen
    seconds : time from the first frame, shape (T,)
    skeleton : the person in the camera frame, metres, shape (T, 15, 3)
    raw : the hand features as seen, shape (T, 3)
    aligned : the invariant features of the invariant recogniser, shape (T, 3)
    actions : the recognisers' actions
    p_raw, p_aligned : ``p_HMM(A | G_1^t)`` of each recogniser, shape (T, n_actions)
    """

    label: str
    view: View
    seconds: np.ndarray
    skeleton: np.ndarray
    raw: np.ndarray
    aligned: np.ndarray
    actions: tuple[str, ...]
    p_raw: np.ndarray
    p_aligned: np.ndarray
    parameters: dict[str, object] = field(default_factory=dict)

    def curves(self) -> pd.DataFrame:
        """Tidy per-frame posteriors: columns view, recogniser, t, seconds, action, p_hmm."""
        T, A = self.p_raw.shape
        frames = []
        for name, p in (("raw", self.p_raw), ("aligned", self.p_aligned)):
            frames.append(
                pd.DataFrame(
                    {
                        "view": self.label,
                        "recogniser": name,
                        "t": np.repeat(np.arange(1, T + 1), A),
                        "seconds": np.repeat(self.seconds, A),
                        "action": np.tile(self.actions, T),
                        "p_hmm": p.ravel(),
                    }
                )
            )
        return tidy(
            pd.concat(frames, ignore_index=True),
            "correspondence_two_views",
            f"synthetic data: one gesture seen as {self.view.describe()}",
            **self.parameters,
        )


def two_views_curves(runs: Sequence[ViewRun]) -> pd.DataFrame:
    """The per-frame posteriors of every view in one tidy frame (:meth:`ViewRun.curves` concatenated)."""
    frames = [r.curves() for r in runs]
    out = pd.concat(frames, ignore_index=True)
    return tidy(
        out,
        "correspondence_two_views",
        "synthetic data: one gesture seen as " + "; ".join(r.view.describe() for r in runs),
        **frames[0].attrs["parameters"],
    )


def two_views(
    raw: Recognizer,
    invariant: Recognizer,
    action: str = "tap",
    views: Sequence[View] = (View(yaw_deg=0.0), View(yaw_deg=120.0, mirror=True)),
    seed: int = 0,
    noise: float = HUMAN_NOISE,
) -> list[ViewRun]:
    """The same synthetic gesture (one seed) seen from each of ``views``, scored frame by frame.

    ``raw`` should be a raw-feature recogniser and ``invariant`` one with invariant features; both stream
    the gesture (:meth:`Recognizer.stream`), so the posteriors are what the robot would see online.
    No spikes or dropouts, so every view has the same frames.
    """
    out = []
    for view in views:
        rng = np.random.default_rng(np.random.SeedSequence([seed, 17]))
        g = synthesize_gesture(action, rng, noise=noise, spike_rate=0.0, dropout_rate=0.0, view=view)
        traj = repair(g.trajectory(), SYNTHETIC_POLICY).pieces[0]
        X = traj.xyz
        p_raw = raw.stream().extend(X)[1]
        p_inv = invariant.stream().extend(X)[1]
        label = f"yaw {view.yaw_deg or 0:g}°" + (", mirrored" if view.mirror else "")
        out.append(
            ViewRun(
                label,
                view,
                traj.t - traj.t[0],
                g.skeleton,
                X,
                invariant.transform(X),
                raw.actions,
                p_raw,
                p_inv[:, [invariant.actions.index(a) for a in raw.actions]],
                {"action": action, "seed": seed, "noise_m": noise, "features": invariant.features.name},
            )
        )
    return out


def one_tap_two_views(
    n_train: int,
    seed: int = 0,
    gesture: int = 1,
    normalise_body: bool = False,
    n_states: int = 6,
    n_mix: int = 1,
) -> list[ViewRun]:
    """Notebook 10's two views: one noise-free tap (seed ``gesture``) seen from the front and, as a mirror
    image, from 120° round (:func:`two_views`), through a raw recogniser and an invariant one (``all``), both
    trained on the front human view (:func:`~glu.studies.correspondence.experiment.train_for`: ``n_train``
    gestures per action, seed ``seed``, ``n_states`` states of ``n_mix`` Gaussians, EM to a tolerance of
    1e-3)."""
    config = TrainingConfig(n_states=n_states, n_mix=n_mix, tol=1e-3)
    raw, invariant = (train_for("human", f, n_train, seed, normalise_body, config) for f in ("raw", ALL))
    views = (
        View(yaw_deg=0.0, normalise_body=normalise_body),
        View(yaw_deg=120.0, mirror=True, normalise_body=normalise_body),
    )
    return two_views(raw, invariant, "tap", views, seed=gesture, noise=0.0)
