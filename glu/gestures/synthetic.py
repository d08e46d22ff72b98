"""Synthetic gestures: seeded skeleton sequences of grasp, tap, touch and push, with real-world variability.

Each sequence is a 15-joint OpenNI skeleton (:data:`glu.gestures.features.OPENNI_JOINTS`) in metres, in the
person's frame (x right, y up, z towards the back), sampled at about 30 frames a second, so the
feature extraction of :mod:`glu.gestures.features` is exercised exactly as on a real skeleton.

The right hand moves from a rest pose (hanging beside the hip) to an object on a table in front and
back, through key poses per action:

* **grasp** — reach above the object, descend, close (a pause), lift it about 25 cm, retract;
* **tap** — reach to the right of the object, strike it laterally to the left (fast), retract;
* **touch** — reach above the object, brief contact on top, retract;
* **push** — reach behind the object (nearer the body), push it forward, retract.

The hand passes smoothly (monotone cubic interpolation) through the key poses, on a mostly
minimum-jerk time course (slow start and end, fastest in the middle). Variability, all drawn
from one seeded generator per sequence:

* **speed** — duration 2.5–5 s (the real repetitions last 2.7–5.5 s), key times jittered; still frames at rest
  before and after;
* **amplitude** — the excursion from rest scaled by 0.85–1.15; object position ± 5 cm;
* **person** — body size 0.85–1.15 (shoulder width 0.28–0.38 m), position in the room, a turn of
  ± 10° about the vertical, slow sway of the torso;
* **sensor** — Gaussian noise of ``noise`` metres on every joint, spikes (a hand joint displaced
  15–40 cm for one frame) with probability ``spike_rate`` per frame, timestamp jitter, and dropouts
  (runs of 3–20 frames with no skeleton: the frames are missing, as in the real logs) with probability
  ``dropout_rate`` per sequence.

How the robot's camera sees the person is a :class:`View`: the person's turn about the vertical axis
relative to the camera (``yaw_deg``; by default a random ± 10°, as in the real recordings), a mirror image
(the movement made with the other hand, or a person facing the robot instead of beside it), the posture
(``standing`` at a table, or ``seated`` with the hand resting on the thigh and the table higher and
further relative to the torso, as in the seated recordings of TCDS), the body size, and whether the
features are normalised by the body's measured size (the 2013 system) or by fixed constants (the 2017 logs,
where body size stays in the features), in the torso's frame or the shoulder line's (``body_frame``,
:func:`glu.gestures.features.to_body_frame`). ``view=None`` and ``View()`` draw the same sequences as
before views existed.

**People unlike the training ones.** ``View(variety=v)`` with ``v > 0`` also gives each person an arm
length of their own (the hand's positions relative to the right shoulder scaled by a factor in
``1 ± 0.15 v``) and a movement style of their own (every key pose of the movement displaced by
``N(0, (0.03 v m)²)`` per axis, its timing by a further ``± 0.04 v``): a seen movement is then no rigid
transform of the generator's standard one, which invariant features cannot undo by construction. The
sensor noise is added after the view, to the skeleton the camera sees.

**Robot mode.** ``View(performer="robot")`` draws the robot's own grasp, tap and touch instead: the
end effector of an iCub-like arm in the robot's body frame (:mod:`glu.gestures.robot`), as a skeleton of
the robot's proportions, so its features are computed exactly as a person's. The robot senses itself by
its joints: no turn unless ``yaw_deg`` is given, and a robot's sensor arguments (``noise=ROBOT_NOISE``, no
spikes or dropouts).

Sequence ``i`` depends only on ``(seed, i)``, so ``synthesize_gestures(10, seed)[:5]`` equals
``synthesize_gestures(5, seed)``. :func:`synthesize_recording` strings repetitions of one action together
with rests in between, with the true segments, to test automatic segmentation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from glu.errors import DataError
from glu.gestures.features import OPENNI_JOINTS, skeleton_features
from glu.gestures.robot import ROBOT_ACTIONS, ROBOT_BODY, robot_hand_path
from glu.gestures.trajectories import RepairPolicy, Trajectory, repair
from glu.gestures.views import DEFAULT_VIEW, View, track
from glu.schema import ACTIONS

_IH = OPENNI_JOINTS.index("right_hand")
GESTURES: tuple[str, ...] = (*ACTIONS, "push")
"""The actions the generator knows (the BN's Action values, plus push)."""

FRAME_RATE = 30.0
SYNTHETIC_POLICY = RepairPolicy(max_interpolate=1.0)
"""Repair of single synthetic gestures: dropouts (at most 20 frames) are interpolated, never split."""

# Body at size 1, relative to the torso, metres (x right, y up, z back). Shoulder distance 0.33 m and
# neck–torso distance 0.23 m: the fallback constants of the original.
BODY = {
    "head": (0.0, 0.45, 0.0),
    "neck": (0.0, 0.23, 0.0),
    "left_shoulder": (-0.165, 0.21, 0.0),
    "right_shoulder": (0.165, 0.21, 0.0),
    "left_elbow": (-0.2, -0.05, 0.02),
    "left_hand": (-0.22, -0.3, 0.04),
    "torso": (0.0, 0.0, 0.0),
    "left_hip": (-0.1, -0.25, 0.0),
    "right_hip": (0.1, -0.25, 0.0),
    "left_knee": (-0.1, -0.35, -0.45),
    "right_knee": (0.1, -0.35, -0.45),
    "left_foot": (-0.1, -0.8, -0.5),
    "right_foot": (0.1, -0.8, -0.5),
}
_REST = np.array([0.25, -0.34, 0.1])
"""Right hand at rest, relative to the torso (size 1): beside the hip, slightly behind."""
OBJECT = np.array([0.06, -0.08, -0.5])
"""The object on the table, relative to the torso (size 1)."""
_SEATED_REST = np.array([0.2, -0.22, -0.22])
"""Seated: the right hand at rest on the thigh, relative to the torso (size 1)."""
SEATED_OBJECT_SHIFT = np.array([0.0, 0.12, -0.2])
"""Seated: the table is higher and further, relative to the torso (size 1)."""
# Key poses: (time fraction, offset from the object or None for rest).
KEYS: dict[str, list[tuple[float, tuple[float, float, float] | None]]] = {
    "grasp": [
        (0.0, None),
        (0.28, (0.0, 0.1, 0.06)),
        (0.38, (0.0, 0.01, 0.0)),
        (0.5, (0.0, 0.0, 0.0)),
        (0.66, (0.0, 0.24, 0.04)),
        (1.0, None),
    ],
    "tap": [
        (0.0, None),
        (0.38, (0.18, 0.03, 0.0)),
        (0.5, (-0.14, 0.01, -0.02)),
        (0.62, (-0.06, 0.07, 0.06)),
        (1.0, None),
    ],
    "touch": [
        (0.0, None),
        (0.36, (0.0, 0.08, 0.04)),
        (0.46, (0.0, 0.02, 0.0)),
        (0.52, (0.0, 0.02, 0.0)),
        (0.64, (0.0, 0.05, 0.1)),
        (1.0, None),
    ],
    "push": [
        (0.0, None),
        (0.34, (0.0, 0.02, 0.14)),
        (0.48, (0.0, 0.01, 0.09)),
        (0.66, (0.0, 0.01, -0.14)),
        (1.0, None),
    ],
}


@dataclass(frozen=True, eq=False)
class SyntheticGesture:
    """One synthetic sequence.

    Attributes
    ----------
    action : one of :data:`GESTURES`
    skeleton : array, shape (n_frames, 15, 3), metres, joints in :data:`glu.gestures.features.OPENNI_JOINTS`
        order
    t : array, shape (n_frames,), seconds (gaps where the skeleton dropped out)
    size : the person's size factor (1 = shoulders 0.33 m apart)
    segments : for a continuous recording, the true (first, last) frames of each repetition
        (1-based, inclusive); for a single gesture, one segment: the whole movement
    view : how it was seen (which also says how its features are normalised)
    """

    action: str
    skeleton: np.ndarray
    t: np.ndarray
    size: float
    segments: tuple[tuple[int, int], ...]
    view: View = DEFAULT_VIEW

    def trajectory(self) -> Trajectory:
        """The features of the skeleton (:func:`glu.gestures.features.skeleton_features`) as a trajectory,
        unrepaired."""
        frame = "body" if self.view.body_frame else "torso"
        xyz, _ = skeleton_features(self.skeleton, measure=self.view.normalise_body, frame=frame)
        return Trajectory.recorded(xyz, self.t, f"synthetic {self.action}")

    def features(self, policy: RepairPolicy = SYNTHETIC_POLICY) -> np.ndarray:
        """The features after repair (dropouts interpolated, spikes replaced), shape (n_frames, 3)."""
        pieces = repair(self.trajectory(), policy).pieces
        return np.concatenate([p.xyz for p in pieces])


@lru_cache(maxsize=512)
def timing(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The time course of a movement of ``n`` frames through its key poses (mostly minimum-jerk: slow start
    and end), and the frames' times ``arange(n) / FRAME_RATE`` (both read-only, cached).

    Returns ``(u, t)``, each shape (n,): ``u`` the fraction of the movement done, rising from 0 to 1; ``t`` in
    seconds from the first frame.
    """
    s = np.linspace(0.0, 1.0, n)
    u = 0.15 * s + 0.85 * s**3 * (10 - 15 * s + 6 * s**2)
    t = np.arange(n) / FRAME_RATE
    u.flags.writeable = t.flags.writeable = False
    return u, t


@dataclass(frozen=True)
class Person:
    """Who performs a synthetic gesture, and where (drawn by :func:`draw_person`)."""

    size: float
    origin: np.ndarray  # torso position in the sensor frame
    yaw: float  # radians
    sway_phase: float
    sway_amp: float


_PERSON_LOW = np.array([0.85, -0.4, -0.15, -2.6, -10.0, 0.0, 0.0])
_PERSON_HIGH = np.array([1.15, 0.4, 0.15, -1.6, 10.0, 2 * np.pi, 0.02])
"""The ranges of a person's uniform draws: size, origin x y z (m), yaw (degrees), sway phase and amplitude."""


def draw_person(rng: np.random.Generator, view: View = DEFAULT_VIEW) -> Person:
    """A person drawn from ``rng`` (in full whatever the view, so a view changes nothing else of the
    sequence), with the view's size and turn if it fixes them; the robot: its own body frame (no camera, no
    sway, no random turn, no draw)."""
    if view.performer == "robot":
        return Person(float(view.size or 1.0), np.zeros(3), float(np.deg2rad(view.yaw_deg or 0.0)), 0.0, 0.0)
    v = rng.uniform(_PERSON_LOW, _PERSON_HIGH)
    size = float(v[0]) if view.size is None else float(view.size)
    yaw = float(np.deg2rad(v[4])) if view.yaw_deg is None else float(np.deg2rad(view.yaw_deg))
    return Person(size, v[1:4].copy(), yaw, float(v[5]), float(v[6]))


def _hand_path(action: str, rng: np.random.Generator, size: float, view: View = DEFAULT_VIEW) -> np.ndarray:
    """Right-hand positions relative to the torso, shape (n_frames, 3), for one repetition."""
    n, times, points = key_poses(action, rng, size, view)
    return pchip(times, points, timing(n)[0])  # SciPy's PchipInterpolator, bit for bit, without its set-up


_HAND_LOW = np.array([2.5, 0.85, -0.05, -0.05, -0.05])
_HAND_HIGH = np.array([5.0, 1.15, 0.05, 0.05, 0.05])
"""The ranges of a repetition's first uniform draws: duration (s), amplitude, object offset x y z (m)."""


def key_poses(
    action: str, rng: np.random.Generator, size: float, view: View
) -> tuple[int, np.ndarray, np.ndarray]:
    """A repetition drawn from ``rng``: its number of frames and its key poses, times (K,) and points (K, 3)
    relative to the torso."""
    duration, amp, *offset = rng.uniform(_HAND_LOW, _HAND_HIGH)
    n = max(int(round(duration * FRAME_RATE)), 12)
    obj, rest = OBJECT + np.array(offset) * np.array([1.0, 0.4, 1.0]), _REST
    if view.posture == "seated":
        obj, rest = obj + SEATED_OBJECT_SHIFT, _SEATED_REST
    rest = rest + rng.normal(0, 0.015, size=3)
    spec = KEYS[action]
    jitter = rng.uniform(-0.02, 0.02, size=len(spec) - 2)
    keys = []
    for j, (tf, off) in enumerate(spec):
        if 0 < j < len(spec) - 1:
            tf = tf + jitter[j - 1]
        p = rest if off is None else rest + amp * (obj + np.asarray(off) - rest)
        keys.append((tf, p * size))
    if view.variety > 0:
        keys = person_style(keys, spec, rng, size, view.variety)
    keys.sort(key=lambda k: k[0])
    return n, np.array([k[0] for k in keys]), np.stack([k[1] for k in keys])


def person_style(
    keys: list[tuple[float, np.ndarray]], spec: list, rng: np.random.Generator, size: float, variety: float
) -> list[tuple[float, np.ndarray]]:
    """A person's own arm length and movement style (see the module docstring), drawn after the key poses.

    ``keys``: the K key poses of :func:`key_poses`, each (time fraction, point of shape (3,) in metres
    relative to the torso); ``spec``: the action's K entries of ``KEYS``. Returns the K key poses moved,
    in the same form.
    """
    arm = rng.uniform(1 - 0.15 * variety, 1 + 0.15 * variety)
    shift = rng.normal(0.0, 0.03 * variety, size=(len(spec), 3))
    warp = rng.uniform(-0.04 * variety, 0.04 * variety, size=len(spec))
    shoulder = np.asarray(BODY["right_shoulder"]) * size
    out = []
    for j, (tf, p) in enumerate(keys):
        inner = 0 < j < len(spec) - 1
        q = p + (shift[j] * size if spec[j][1] is not None else 0.0)
        out.append(
            (float(np.clip(tf + warp[j], 0.05, 0.95)) if inner else tf, shoulder + arm * (q - shoulder))
        )
    return out


def _skeletons(
    hand: np.ndarray, person: Person, t: np.ndarray, rng: np.random.Generator, view: View = DEFAULT_VIEW
) -> np.ndarray:
    """Full skeletons in the sensor frame, shape (n_frames, 15, 3), for hand positions relative to the
    torso."""
    if view.mirror:
        hand = hand * np.array([-1.0, 1.0, 1.0])
    n = len(hand)
    s = person.size
    shape = ROBOT_BODY if view.performer == "robot" else BODY
    body = np.array([shape.get(j, (0.0, 0.0, 0.0)) for j in OPENNI_JOINTS]) * s
    rel = np.broadcast_to(body, (n, len(OPENNI_JOINTS), 3)).copy()
    ih, ie, ish = OPENNI_JOINTS.index("right_hand"), OPENNI_JOINTS.index("right_elbow"), 3
    rel[:, ih] = hand
    shoulder = body[ish]
    mid = 0.5 * (shoulder + hand)
    rel[:, ie] = mid + np.array([0.06, -0.06, 0.05]) * s  # elbow out, down and back of the shoulder–hand line
    sway = person.sway_amp * np.sin(2 * np.pi * 0.25 * t + person.sway_phase)
    c, si = np.cos(person.yaw), np.sin(person.yaw)
    rot = np.array([[c, 0.0, si], [0.0, 1.0, 0.0], [-si, 0.0, c]])
    world = rel @ rot.T + person.origin
    world[:, :, 0] += sway[:, None]
    return world


class SensorDraws(NamedTuple):
    """The sensor's random draws for one sequence of frames (:func:`sensor_draws`)."""

    noise: np.ndarray | None  # (n, 15, 3), or None without noise
    spikes: np.ndarray  # bool (n,): frames whose hand joint is displaced …
    spike: np.ndarray | None  # … by these (n_spikes, 3), or None without a spike
    jitter: np.ndarray  # (n,) added to the timestamps
    keep: np.ndarray | None  # bool (n,): the frames left after a dropout, or None without one


def sensor_draws(
    rng: np.random.Generator, n: int, noise: float, spike_rate: float, dropout_rate: float
) -> SensorDraws:
    """What the sensor does to ``n`` frames (see the module docstring), drawn from ``rng``."""
    eps = rng.normal(0.0, noise, size=(n, len(OPENNI_JOINTS), 3)) if noise > 0 else None
    spikes = rng.random(n) < spike_rate
    k = int(spikes.sum())
    d = None
    if k:
        d = rng.normal(size=(k, 3))
        d *= (rng.uniform(0.15, 0.4, size=k) / np.linalg.norm(d, axis=1))[:, None]
    jitter = rng.normal(0.0, 0.002, size=n)
    keep = None
    if n > 30 and rng.random() < dropout_rate:
        length = int(rng.integers(3, 21))
        start = int(rng.integers(5, n - length - 5))
        keep = np.ones(n, dtype=bool)
        keep[start : start + length] = False
    return SensorDraws(eps, spikes, d, jitter, keep)


def sensed(
    skel: np.ndarray, t: np.ndarray, draws: SensorDraws, joints: np.ndarray | slice = slice(None)
) -> tuple[np.ndarray, np.ndarray]:
    """The skeletons and timestamps the sensor reports: ``draws`` applied to ``skel`` (n, J, 3), metres,
    whose joints are ``OPENNI_JOINTS[joints]`` (the right hand among them), and to its times ``t`` (n,),
    seconds. Returns the skeletons (n_kept, J, 3) and times (n_kept,): the frames left after a dropout."""
    skel = skel + draws.noise[:, joints] if draws.noise is not None else skel.copy()
    if draws.spike is not None:
        skel[draws.spikes, np.arange(len(OPENNI_JOINTS))[joints].tolist().index(_IH)] += draws.spike
    t = t + draws.jitter
    return (skel, t) if draws.keep is None else (skel[draws.keep], t[draws.keep])


def _check(n: int, noise: float, spike_rate: float, dropout_rate: float) -> None:
    if n < 0:
        raise DataError(f"number of sequences {n} is negative")
    if not noise >= 0 or not 0 <= spike_rate <= 1 or not 0 <= dropout_rate <= 1:
        raise DataError("noise must be ≥ 0 (metres); spike_rate and dropout_rate in [0, 1]")


def synthesize_gesture(
    action: str,
    rng: np.random.Generator,
    *,
    noise: float = 0.01,
    spike_rate: float = 0.005,
    dropout_rate: float = 0.2,
    rest_frames: tuple[int, int] = (3, 15),
    view: View | None = None,
) -> SyntheticGesture:
    """One synthetic repetition of ``action`` drawn with ``rng``, seen as ``view`` (see the module
    docstring)."""
    view = view or DEFAULT_VIEW
    check_action(action, view)
    person = draw_person(rng, view)
    if view.performer == "robot":
        move = robot_hand_path(action, rng, person.size)
    else:
        move = _hand_path(action, rng, person.size, view)
    pre, post = (int(rng.integers(rest_frames[0], rest_frames[1] + 1)) for _ in range(2))
    hand = np.concatenate([np.repeat(move[:1], pre, 0), move, np.repeat(move[-1:], post, 0)])
    t = timing(len(hand))[1]
    skel = track(_skeletons(hand, person, t, rng, view), person.yaw, view)  # what the tracker reports
    true = ((pre + 1, pre + len(move)),)
    skel, t_obs = sensed(skel, t, sensor_draws(rng, len(skel), noise, spike_rate, dropout_rate))
    return SyntheticGesture(action, skel, t_obs, person.size, true, view)


def check_action(action: str, view: View) -> None:
    """Refuse, in one line, an action the performer of ``view`` (a person or the robot) cannot perform."""
    allowed = ROBOT_ACTIONS if view.performer == "robot" else GESTURES
    if action not in allowed:
        raise DataError(f"unknown action {action!r} for a {view.performer}; allowed: {', '.join(allowed)}")


def synthesize_gestures(
    n: int,
    seed: int = 0,
    *,
    actions: tuple[str, ...] = GESTURES,
    noise: float = 0.01,
    spike_rate: float = 0.005,
    dropout_rate: float = 0.2,
    view: View | None = None,
) -> list[SyntheticGesture]:
    """``n`` synthetic gestures, actions in turn (``actions[i % len(actions)]``), sequence i seeded by (seed,
    i).

    Parameters
    ----------
    n : number of sequences (any number ≥ 0)
    seed : the random seed
    actions : which actions, in turn
    noise : standard deviation of the sensor noise on every joint, metres
    spike_rate : probability that a frame's hand joint is an outlier
    dropout_rate : probability that a sequence loses a run of 3–20 frames
    view : how the camera sees the person (:class:`View`; default: facing it, turned by a random ± 10°),
        or ``View(performer="robot")`` for the robot's own movements (then only grasp, tap and touch)
    """
    _check(n, noise, spike_rate, dropout_rate)
    for a in actions:
        check_action(a, view or DEFAULT_VIEW)
    children = np.random.SeedSequence(seed).spawn(n)
    return [
        synthesize_gesture(
            actions[i % len(actions)],
            np.random.default_rng(children[i]),
            noise=noise,
            spike_rate=spike_rate,
            dropout_rate=dropout_rate,
            view=view,
        )
        for i in range(n)
    ]


def synthesize_recording(
    action: str,
    n_repetitions: int,
    seed: int = 0,
    *,
    noise: float = 0.01,
    spike_rate: float = 0.0,
    rest_seconds: tuple[float, float] = (1.0, 2.0),
    placements: Sequence[tuple[int, int]] | None = None,
    n_frames: int | None = None,
) -> SyntheticGesture:
    """A continuous recording of one person repeating ``action``, resting in between (no dropouts).

    Returns a :class:`SyntheticGesture` whose ``segments`` are the true repetitions (1-based frames).

    Parameters
    ----------
    action, n_repetitions, seed : what is repeated, how often, and the seed (the same arguments give the
        same recording)
    noise, spike_rate : sensor noise (m) and outlier rate, as :func:`synthesize_gesture`
    rest_seconds : the range of the rests between repetitions
    placements : optional (first, last) frames (1-based, inclusive) of each repetition, in order and
        apart; each movement is then resampled to its placement and the rests fill the frames between
        (``n_repetitions`` is ``len(placements)``)
    n_frames : with ``placements``, the length of the recording (default: 60 frames after the last)
    """
    if action not in KEYS:
        raise DataError(f"unknown action {action!r}; allowed: {', '.join(GESTURES)}")
    if placements is not None:
        n_repetitions = len(placements)
        ends = [0, *(b for _, b in placements)]
        starts = [a for a, _ in placements]
        if any(a < 2 or b < a + 9 for a, b in placements) or any(
            a <= e for a, e in zip(starts, ends[:-1], strict=True)
        ):
            raise DataError(
                f"placements {list(placements)} must be in order, apart, after frame 1, ≥ 10 frames each"
            )
        n_frames = n_frames or ends[-1] + 60
        if n_frames < ends[-1]:
            raise DataError(f"n_frames={n_frames} is shorter than the last placement ({ends[-1]})")
    if n_repetitions < 1:
        raise DataError("a recording needs at least one repetition")
    _check(n_repetitions, noise, spike_rate, 0.0)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 7, GESTURES.index(action)]))
    person = draw_person(rng)
    parts, segments, n = [], [], 0
    for k in range(n_repetitions + 1):
        if placements is None:
            rest = int(rng.uniform(*rest_seconds) * FRAME_RATE)
        else:
            rest = (placements[k][0] - 1 if k < n_repetitions else n_frames) - n
        pose = _REST * person.size + rng.normal(0, 0.01, size=3)
        parts.append(np.repeat(pose[None], rest, 0))
        n += rest
        if len(segments) == n_repetitions:
            break
        move = _hand_path(action, rng, person.size)
        if placements is not None:
            a, b = placements[k]
            move = _resample(move, b - a + 1)
        move = move - move[0] + pose  # start from the current rest pose
        parts.append(move)
        segments.append((n + 1, n + len(move)))
        n += len(move)
    hand = np.concatenate(parts)
    # smooth the joins between a movement's end and the next rest pose
    from scipy.ndimage import uniform_filter1d

    hand = uniform_filter1d(hand, 5, axis=0, mode="nearest")
    t = timing(len(hand))[1]
    skel = _skeletons(hand, person, t, rng)
    skel, t_obs = sensed(skel, t, sensor_draws(rng, len(skel), noise, spike_rate, 0.0))
    return SyntheticGesture(action, skel, t_obs, person.size, tuple(segments))


def _resample(path: np.ndarray, n: int) -> np.ndarray:
    """``path`` (shape (m, 3)) linearly resampled to ``n`` frames with the same start and end."""
    s = np.linspace(0.0, 1.0, len(path))
    u = np.linspace(0.0, 1.0, n)
    return np.stack([np.interp(u, s, path[:, i]) for i in range(path.shape[1])], axis=1)


# ------------------------------------------------------------------ monotone cubic interpolation (PCHIP)
# Monotone piecewise-cubic interpolation (PCHIP) through a handful of key points, fast.
#
# The synthetic gestures pass through five or six key poses (:mod:`glu.gestures.synthetic`). SciPy's
# ``PchipInterpolator`` does exactly this but costs about 0.3 ms per call in set-up, a third of a synthetic
# gesture; a corpus of a million episodes calls it a million times. :func:`pchip` is the same algorithm —
# Fritsch–Butland derivatives (weighted harmonic means of the neighbouring slopes, 0 at a change of sign),
# the one-sided three-point end derivatives SciPy takes from Moler's ``pchiptx``, and the cubic Hermite
# polynomial evaluated in SciPy's order — in a few array operations, and gives SciPy's values bit for bit
# (tested).


def pchip(x: np.ndarray, y: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The PCHIP interpolant through ``(x_k, y_k)`` at ``u``: :func:`pchip_many` of one curve.

    Parameters
    ----------
    x : array, shape (K,) — strictly increasing, K ≥ 2
    y : array, shape (K, D) — values at the key points
    u : array, shape (N,) — where to evaluate (outside [x_0, x_{K-1}] the end cubics are extended)

    Returns
    -------
    array, shape (N, D)
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    return pchip_many(x[None], y[None], [np.asarray(u, dtype=float)])[0]


def pchip_many(x: np.ndarray, y: np.ndarray, u: list[np.ndarray]) -> list[np.ndarray]:
    """:func:`pchip` of many curves with the same number of key points, in a few array operations.

    Every value is computed by elementwise IEEE operations, so batching changes nothing: each curve's
    values are SciPy's bit for bit, whatever else is in the batch.

    Parameters
    ----------
    x : array, shape (B, K) — each row strictly increasing, K ≥ 2
    y : array, shape (B, K, D)
    u : B arrays of shapes (N_b,) — where to evaluate each curve

    Returns
    -------
    B arrays of shapes (N_b, D)
    """
    x = np.asarray(x, dtype=float)
    Y = np.asarray(y, dtype=float)
    B, K, D = Y.shape
    h = (x[:, 1:] - x[:, :-1])[:, :, None]  # (B, K-1, 1)
    m = (Y[:, 1:] - Y[:, :-1]) / h  # (B, K-1, D)
    d = np.zeros((B, K, D))
    if K == 2:  # one segment: its slope at both ends
        d[:] = m
    else:
        a, b = m[:, :-1], m[:, 1:]
        hk, hk1 = h[:, 1:], h[:, :-1]
        w1, w2 = 2 * hk + hk1, hk + 2 * hk1
        with np.errstate(divide="ignore", invalid="ignore"):
            inner = 1.0 / ((w1 / a + w2 / b) / (w1 + w2))
        zero = (np.sign(b) != np.sign(a)) | (b == 0) | (a == 0)
        d[:, 1:-1] = np.where(zero, 0.0, inner)
        d[:, 0] = _edges(h[:, 0], h[:, 1], m[:, 0], m[:, 1])
        d[:, -1] = _edges(h[:, -1], h[:, -2], m[:, -1], m[:, -2])
    t = (d[:, :-1] + d[:, 1:] - 2 * m) / h  # cubic Hermite coefficients, as SciPy's CubicHermiteSpline
    c0, c1, c2, c3 = t / h, (m - d[:, :-1]) / h - t, d[:, :-1], Y[:, :-1]
    n = [len(v) for v in u]
    uu = np.concatenate(u)
    row = np.repeat(np.arange(B), n)
    xr = x[row]  # (N, K)
    k = np.clip((xr <= uu[:, None]).sum(axis=1) - 1, 0, K - 2)  # searchsorted(x, u, side="right") - 1
    s = (uu - xr[np.arange(len(uu)), k])[:, None]
    z = s
    out = c3[row, k] + c2[row, k] * z
    z = z * s
    out = out + c1[row, k] * z
    z = z * s
    out = out + c0[row, k] * z
    return np.split(out, np.cumsum(n)[:-1])


def _edges(h0: np.ndarray, h1: np.ndarray, m0: np.ndarray, m1: np.ndarray) -> np.ndarray:
    """The one-sided three-point end derivatives (SciPy's, from Moler's ``pchiptx``): h0, h1 of shape
    (B, 1), m0, m1 of shape (B, D)."""
    d = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    overshoot = (np.sign(m0) != np.sign(m1)) & (np.abs(d) > 3.0 * np.abs(m0))
    return np.where(np.sign(d) != np.sign(m0), 0.0, np.where(overshoot, 3.0 * m0, d))
