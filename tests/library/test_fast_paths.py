"""The corpus's fast paths equal the straightforward ones bit for bit: gestures, PCHIP, spike check, repair.

The corpus (:mod:`glu.studies.corpus_evaluation.corpus`) simulates a chunk of episodes at once
(:mod:`glu.gestures.synthetic_batch`, :func:`glu.gestures.trajectories.repaired_many`,
:func:`glu.gestures.synthetic.pchip_many`); its results must be those of one gesture at a time
(``synthesize_gesture(...).features()``, SciPy's ``PchipInterpolator`` and ``median_filter``,
:func:`glu.gestures.trajectories.repair`), exactly.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator
from scipy.ndimage import median_filter

from glu.bn import learn_bn, make_engine
from glu.data import load_experiments
from glu.errors import DataError
from glu.gestures.synthetic import GESTURES, SYNTHETIC_POLICY, View, pchip_many, synthesize_gesture
from glu.gestures.synthetic_batch import gesture_features
from glu.gestures.trajectories import (
    DEFAULT_POLICY,
    DETECT_ONLY,
    RepairPolicy,
    Trajectory,
    repair,
    repaired_many,
    spike_deviations,
)
from glu.studies.corpus_evaluation.corpus import simulate_chunk
from glu.studies.episodes import GESTURE_KEY, VIEWPOINTS, Condition, GestureSettings

VIEWS = [
    None,
    View(yaw_deg=40.0),
    View(posture="seated"),
    View(mirror=True, size=1.2),
    View(normalise_body=False, yaw_deg=90.0),
    View(performer="robot"),
]
SENSORS = [
    dict(noise=0.02),
    dict(noise=0.0, spike_rate=0.0, dropout_rate=0.0),
    dict(noise=0.05, spike_rate=0.1, dropout_rate=1.0),
    dict(noise=0.01, spike_rate=0.6),
]


def same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("view", VIEWS, ids=lambda v: v.describe() if v else "default")
@pytest.mark.parametrize("sensor", SENSORS, ids=["default", "clean", "noisy", "spiky"])
def test_batch_gestures_equal_one_at_a_time(view, sensor):
    actions = ("grasp", "tap", "touch") if view and view.performer == "robot" else GESTURES
    acts = [actions[i % len(actions)] for i in range(24)]
    rngs = lambda: [np.random.default_rng([7, i]) for i in range(24)]  # noqa: E731
    fast = gesture_features(acts, rngs(), view=view, **sensor)
    for i, (a, r) in enumerate(zip(acts, rngs(), strict=True)):
        g = synthesize_gesture(a, r, view=view, **sensor)
        assert same(fast.features[i], g.features()), (i, a)
        assert fast.duration[i] == g.t[-1] - g.t[0] and fast.size[i] == g.size


def test_chunk_equals_the_episode_by_episode_reference():
    """simulate_chunk against the loop it replaced: one synthesize_gesture per episode, then its features."""
    engine = make_engine(learn_bn(load_experiments("synthetic")))
    for cond, settings in [
        (Condition(0.02, "front"), GestureSettings()),
        (Condition(0.0, "seated"), GestureSettings(0.2, 1.0)),
    ]:
        chunk = simulate_chunk(engine, cond, 5, 1, 30, 40, gestures=settings)
        actions = engine.bn.schema.values_of("Action")
        for i in range(30):
            rng = np.random.default_rng(
                np.random.SeedSequence(5, spawn_key=(GESTURE_KEY, 0, 40 + i))
            )  # replication 0
            g = synthesize_gesture(
                actions[chunk.codes["Action"][i]],
                rng,
                noise=cond.noise,
                spike_rate=settings.spike_rate,
                dropout_rate=settings.dropout_rate,
                view=VIEWPOINTS[cond.viewpoint],
            )
            x = g.features()
            assert same(chunk.features[i], x)
            row = chunk.episodes.iloc[i]
            assert (row.n_frames, row.duration_s, row.body_size) == (len(x), g.t[-1] - g.t[0], g.size)


def test_pchip_many_equals_scipy_bit_for_bit():
    rng = np.random.default_rng(11)
    for K in range(2, 8):
        B = 40
        x = np.sort(rng.uniform(0, 1, (B, K)), axis=1)
        x[:, 0], x[:, -1] = 0.0, 1.0
        x = x[(np.diff(x, axis=1) > 1e-6).all(axis=1)]
        y = rng.normal(size=(len(x), K, 3))
        y[::3, 1:3] = y[::3, 1:2]  # flat stretches: zero slopes
        y[1::3] = np.cumsum(np.abs(y[1::3]), axis=1)  # monotone data
        u = [np.linspace(-0.1, 1.1, int(rng.integers(1, 90))) for _ in range(len(x))]
        for b, v in enumerate(pchip_many(x, y, u)):
            assert same(v, PchipInterpolator(x[b], y[b], axis=0)(u[b]))


@pytest.mark.parametrize("window", [3, 5, 7, 9])
def test_spike_deviations_equal_scipy_median_filter(window):
    rng = np.random.default_rng(window)
    xyzs = [rng.normal(size=(int(n), 3)) for n in rng.integers(0, 60, 50)]
    xyzs[3][5:9] = xyzs[3][5]  # ties
    xyzs.append(np.round(rng.normal(size=(40, 3)), 1))  # many ties
    for x, dev in zip(xyzs, spike_deviations(xyzs, window), strict=True):
        ref = np.linalg.norm(x - median_filter(x, size=(window, 1), mode="nearest"), axis=1)
        assert same(dev, ref if len(x) >= window else np.zeros(len(x)))


def trajectories(rng, k=60):
    """Random trajectories with spikes, dropouts (short and long gaps), a missing frame, tiny ones."""
    out = []
    for i in range(k):
        n = int(rng.integers(2, 120)) if i % 10 else int(rng.integers(1, 4))
        xyz = np.cumsum(rng.normal(scale=0.05, size=(n, 3)), axis=0)
        spikes = rng.random(n) < [0.0, 0.05, 0.4, 0.9][i % 4]
        xyz[spikes] += rng.normal(scale=1.0, size=(int(spikes.sum()), 3))
        t = np.arange(n) / 30 + rng.normal(0, 0.002, n)
        t = np.sort(t) + np.arange(n) * 1e-4
        if n > 30 and i % 3 == 0:
            a = int(rng.integers(5, n - 25))
            t[a:] += [0.3, 0.9, 2.0][i % 9 // 3]
        if i % 17 == 5 and n > 3:
            xyz[2, 1] = np.nan
        out.append((xyz, t))
    return out


POLICIES = [
    SYNTHETIC_POLICY,
    DEFAULT_POLICY,
    DETECT_ONLY,
    RepairPolicy(spikes="drop", max_interpolate=0.1),
    RepairPolicy(long_gaps="keep", spike_window=5, min_piece=3),
    RepairPolicy(spike_threshold=np.inf),
    RepairPolicy(spike_window=3, spike_threshold=0.05, min_piece=1),
]


@pytest.mark.parametrize("policy", POLICIES, ids=range(len(POLICIES)))
def test_repaired_many_equals_repair(policy):
    rng = np.random.default_rng(3)
    data = trajectories(rng)
    expected = []
    for xyz, t in data:
        try:
            traj = Trajectory(xyz, t, np.arange(1, len(t) + 1), np.ones(len(t), bool))
            expected.append(np.concatenate([p.xyz for p in repair(traj, policy).pieces]))
        except DataError:
            expected.append(None)
    ok = [i for i, e in enumerate(expected) if e is not None]
    got = repaired_many([data[i][0] for i in ok], [data[i][1] for i in ok], policy)
    assert all(same(g, expected[i]) for g, i in zip(got, ok, strict=True))
    for i, e in enumerate(expected):
        if e is None:
            with pytest.raises(DataError):
                repaired_many([data[i][0]], [data[i][1]], policy)
