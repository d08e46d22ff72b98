"""Many synthetic gestures' repaired features at once: the corpus's fast path, bit for bit the same.

A simulated corpus (:mod:`glu.studies.corpus_evaluation.corpus`) needs, for each of a million episodes, only
the repaired features of one synthetic gesture (:meth:`glu.gestures.synthetic.SyntheticGesture.features`).
:func:`gesture_features` computes them for a whole chunk of episodes: each episode's generator draws exactly
the numbers :func:`~glu.gestures.synthetic.synthesize_gesture` draws, in the same order, and then the work is
shared across the episodes — the minimum-jerk hand paths of all episodes in a few array operations
(:func:`glu.gestures.synthetic.pchip_many`), the sway of all frames at once, the running repair of all
episodes at once (:func:`glu.gestures.trajectories.repaired_many`), and only the joints the features use.
Every number is computed by the same IEEE operations as the one-gesture path (elementwise operations do not
depend on how the arrays are batched; the rotation of each skeleton is the same matrix product; reductions
run per episode, on the same arrays), so the features are identical, bit for bit, to
``synthesize_gesture(...).features()`` (tested).

Example
-------
>>> import numpy as np
>>> from glu.gestures.synthetic import synthesize_gesture
>>> rngs = lambda: [np.random.default_rng(i) for i in range(3)]
>>> fast = gesture_features(["tap", "grasp", "touch"], rngs(), noise=0.02)
>>> slow = [synthesize_gesture(a, r, noise=0.02) for a, r in zip(["tap", "grasp", "touch"], rngs())]
>>> all(np.array_equal(x, g.features()) for x, g in zip(fast.features, slow))
True
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from glu.gestures.features import skeleton_features
from glu.gestures.synthetic import (
    BODY,
    DEFAULT_VIEW,
    OPENNI_JOINTS,
    SYNTHETIC_POLICY,
    View,
    check_action,
    draw_person,
    key_poses,
    pchip_many,
    sensed,
    sensor_draws,
    synthesize_gesture,
    timing,
)
from glu.gestures.trajectories import RepairPolicy, repaired_many
from glu.gestures.views import track

_JOINT_NAMES = ("right_hand", "torso", "left_shoulder", "right_shoulder", "neck")
"""The joints the features use, in the order of :func:`_skeleton`'s columns."""
_JOINTS = np.array([OPENNI_JOINTS.index(j) for j in _JOINT_NAMES])
_BODY_ARRAY = np.array([BODY.get(j, (0.0, 0.0, 0.0)) for j in OPENNI_JOINTS])


class GestureBatch(NamedTuple):
    """The repaired features of many synthetic gestures, and what a corpus records of each.

    Attributes
    ----------
    features : n arrays of shape (T_i, 3), as :meth:`~glu.gestures.synthetic.SyntheticGesture.features`
    duration : array, shape (n,), seconds from the first to the last observed frame
    size : array, shape (n,), the person's size factor
    """

    features: list[np.ndarray]
    duration: np.ndarray
    size: np.ndarray


def gesture_features(
    actions: Sequence[str],
    rngs: Sequence[np.random.Generator],
    *,
    noise: float = 0.01,
    spike_rate: float = 0.005,
    dropout_rate: float = 0.2,
    rest_frames: tuple[int, int] = (3, 15),
    view: View | None = None,
    policy: RepairPolicy = SYNTHETIC_POLICY,
) -> GestureBatch:
    """``synthesize_gesture(actions[i], rngs[i], ...).features(policy)`` for every i, computed together.

    Parameters
    ----------
    actions : n actions (:data:`~glu.gestures.synthetic.GESTURES`)
    rngs : n generators, one per gesture (each is advanced exactly as by ``synthesize_gesture``)
    noise, spike_rate, dropout_rate, rest_frames, view : as :func:`~glu.gestures.synthetic.synthesize_gesture`
    policy : the repair (:meth:`~glu.gestures.synthetic.SyntheticGesture.features`)
    """
    view = view or DEFAULT_VIEW
    sensor = {
        "noise": noise,
        "spike_rate": spike_rate,
        "dropout_rate": dropout_rate,
        "rest_frames": rest_frames,
    }
    if view.performer == "robot":  # the robot's own movements: one at a time
        gs = [synthesize_gesture(a, r, **sensor, view=view) for a, r in zip(actions, rngs, strict=True)]
        return GestureBatch(
            [g.features(policy) for g in gs],
            np.array([g.t[-1] - g.t[0] for g in gs], dtype=float).reshape(len(gs)),
            np.array([g.size for g in gs], dtype=float).reshape(len(gs)),
        )
    for a in set(actions):
        check_action(a, view)
    episodes = [_draws(a, rng, view, **sensor) for a, rng in zip(actions, rngs, strict=True)]
    draws = [e[0] for e in episodes]
    moves = _hand_paths([e[1] for e in episodes], [e[2] for e in episodes], [w[1] for w in draws])
    # the sway of every frame of every episode, in one call
    phase = np.concatenate([np.full(w[1] + w[2] + w[3], w[0].sway_phase) for w in draws])
    amps = np.concatenate([np.full(w[1] + w[2] + w[3], w[0].sway_amp) for w in draws])
    tt = np.concatenate([timing(w[1] + w[2] + w[3])[1] for w in draws])
    sway_all = amps * np.sin(2 * np.pi * 0.25 * tt + phase)
    xyzs, ts, duration, sizes = [], [], np.empty(len(draws)), np.empty(len(draws))
    at = 0
    for i, (w, move) in enumerate(zip(draws, moves, strict=True)):
        person, m, pre, post, sensor = w
        nf = pre + m + post
        hand = np.concatenate([np.repeat(move[:1], pre, 0), move, np.repeat(move[-1:], post, 0)])
        skel = _skeleton(hand, person.size, person.yaw, person.origin, sway_all[at : at + nf], view)
        at += nf
        skel, t = sensed(skel, timing(nf)[1], sensor, _JOINTS)
        frame = "body" if view.body_frame else "torso"
        xyzs.append(skeleton_features(skel, _JOINT_NAMES, measure=view.normalise_body, frame=frame)[0])
        ts.append(t)
        duration[i], sizes[i] = t[-1] - t[0], person.size
    return GestureBatch(repaired_many(xyzs, ts, policy), duration, sizes)


def _draws(
    action: str,
    rng: np.random.Generator,
    view: View,
    *,
    noise: float,
    spike_rate: float,
    dropout_rate: float,
    rest_frames: tuple[int, int],
) -> tuple[tuple, np.ndarray, np.ndarray]:
    """One episode's random draws, the same in the same order as ``synthesize_gesture``'s (its person,
    ``_hand_path`` and :func:`~glu.gestures.synthetic.sensor_draws`): the drawn values, and the key times
    and points of its hand path."""
    person = draw_person(rng, view)
    m, times, points = key_poses(action, rng, person.size, view)
    pre, post = (int(rng.integers(rest_frames[0], rest_frames[1] + 1)) for _ in range(2))
    sensor = sensor_draws(rng, pre + m + post, noise, spike_rate, dropout_rate)
    return (person, m, pre, post, sensor), times, points


def _hand_paths(times: list[np.ndarray], points: list[np.ndarray], n: list[int]) -> list[np.ndarray]:
    """``_min_jerk_path`` of every episode: PCHIP through its key poses, per number of keys at once."""
    out: list[np.ndarray] = [np.empty(0)] * len(times)
    by_k: dict[int, list[int]] = {}
    for i, x in enumerate(times):
        by_k.setdefault(len(x), []).append(i)
    for idx in by_k.values():
        x = np.stack([times[i] for i in idx])
        y = np.stack([points[i] for i in idx])
        u = [timing(n[i])[0] for i in idx]
        for i, path in zip(idx, pchip_many(x, y, u), strict=True):
            out[i] = path
    return out


def _skeleton(
    hand: np.ndarray, size: float, yaw: float, origin: np.ndarray, sway: np.ndarray, view: View
) -> np.ndarray:
    """The joints :data:`_JOINTS` of ``_skeletons``' skeleton in the sensor frame, shape (n_frames, 5, 3).

    The rotation is the same matrix product over the full 15-joint skeleton as ``_skeletons`` (each
    output row depends only on its own joint; the elbow, unused by the features, is left at rest).
    """
    if view.mirror:
        hand = hand * np.array([-1.0, 1.0, 1.0])
    nf = len(hand)
    body = _BODY_ARRAY * size
    rel = np.empty((nf, len(OPENNI_JOINTS), 3))
    rel[:] = body
    rel[:, _JOINTS[0]] = hand
    c, si = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, 0.0, si], [0.0, 1.0, 0.0], [-si, 0.0, c]])
    if view.tracker != "ideal":  # the tracker needs every joint (glu.gestures.views.track)
        world = rel @ rot.T + origin
        world[:, :, 0] += sway[:, None]
        return track(world, yaw, view)[:, _JOINTS]
    world = (rel @ rot.T)[:, _JOINTS] + origin
    world[:, :, 0] += sway[:, None]
    return world
