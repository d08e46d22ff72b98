"""The simulated world's effects that depend on the gesture (glu.studies.episodes): the speeds replayed
from the generator's own draws, and the effects redrawn from them, against the generator and closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from glu.errors import DataError
from glu.gestures.features import OPENNI_JOINTS
from glu.gestures.synthetic import FRAME_RATE, View, synthesize_gesture
from glu.studies.episodes import (
    GESTURE_WORLDS,
    GestureEffects,
    effects_given_gesture,
    gesture_speed,
    speed_quantile,
)


def _rngs(n, base=0):
    return [np.random.default_rng(np.random.SeedSequence(base, spawn_key=(1, i))) for i in range(n)]


@pytest.mark.parametrize(
    "view", [View(), View(yaw_deg=40.0), View(posture="seated"), View(yaw_deg=90, mirror=True, variety=1.0)]
)
def test_speed_replays_the_generators_duration(view):
    """The movement's length in frames (the generator's true segment) is round(duration · 30), at least 12."""
    sp = gesture_speed(_rngs(40))
    for i, (rng, action) in enumerate(zip(_rngs(40), ["grasp", "tap", "touch", "push"] * 10, strict=True)):
        g = synthesize_gesture(action, rng, view=view)
        ((first, last),) = g.segments
        assert last - first + 1 == max(int(round(sp.duration[i] * FRAME_RATE)), 12)


def test_speed_is_how_fast_the_hand_moves():
    """Independent of the replay: the hand's peak speed relative to the torso (noise-free, size removed)
    rises with the replayed speed for every action (Spearman ρ > 0.8 over 60 gestures)."""
    sp = gesture_speed(_rngs(60))
    for action in ("grasp", "tap", "touch"):
        peak = []
        for rng in _rngs(60):
            g = synthesize_gesture(
                action, rng, noise=0.0, spike_rate=0.0, dropout_rate=0.0, view=View(yaw_deg=0.0)
            )
            hand = (
                g.skeleton[:, OPENNI_JOINTS.index("right_hand")] - g.skeleton[:, OPENNI_JOINTS.index("torso")]
            )
            peak.append(np.linalg.norm(np.diff(hand, axis=0), axis=1).max() * FRAME_RATE / g.size)
        assert stats.spearmanr(sp.speed, peak).statistic > 0.8


def test_quantile_is_uniform_over_gestures():
    """The closed-form CDF of amplitude / duration makes the quantiles uniform (KS test on 4,000 gestures;
    the draws are fixed, so the test is deterministic) and follows the speed."""
    sp = gesture_speed(_rngs(4000, base=7))
    assert stats.kstest(sp.quantile, "uniform").pvalue > 0.01
    order = np.argsort(sp.speed)
    assert (np.diff(sp.quantile[order]) >= 0).all()
    assert speed_quantile(np.array([0.85 / 5.0 - 1e-9, 1.15 / 2.5 + 1e-9])).tolist() == [0.0, 1.0]
    # against Monte Carlo at a few speeds
    rng = np.random.default_rng(0)
    s = rng.uniform(0.85, 1.15, 200_000) / rng.uniform(2.5, 5.0, 200_000)
    for v in (0.2, 0.27, 0.3, 0.4):
        assert speed_quantile(np.array([v]))[0] == pytest.approx((s <= v).mean(), abs=0.005)


@pytest.fixture(scope="module")
def engine(source):
    from glu.bn import learn_bn, make_engine
    from glu.data import load_experiments

    return make_engine(learn_bn(load_experiments(source)))


def _world(engine, n, action="tap", seed=0):
    from glu.bn.sampling import sample

    schema = engine.bn.schema
    fixed = {"Action": np.full(n, schema.values_of("Action").index(action)), "Color": np.zeros(n, int),
             "Shape": np.zeros(n, int), "Size": np.zeros(n, int)}  # fmt: skip
    return sample(engine, fixed, np.random.default_rng(seed)), fixed


def test_inactive_world_changes_nothing(engine):
    codes, _ = _world(engine, 50)
    rng = np.random.default_rng(1)
    state = rng.bit_generator.state
    out = effects_given_gesture(engine, codes, np.linspace(0, 1, 50), GESTURE_WORLDS["action"], rng)
    assert all(np.array_equal(out[k], codes[k]) for k in codes) and rng.bit_generator.state == state


def test_speed_tilts_the_effect_by_the_closed_form(engine):
    """At speed quantile q, p(ObjVel = v) ∝ p_BN(v | object, tap) · exp(λ (2q − 1) r_v), r = (−1, 0, 1);
    the other effects are drawn given the new ObjVel (p_BN(HandVel | object, tap, ObjVel))."""
    n = 30_000
    codes, fixed = _world(engine, n)
    lam, q = 1.5, 0.9
    out = effects_given_gesture(
        engine, codes, np.full(n, q), GestureEffects(speed_effect=lam), np.random.default_rng(2)
    )
    ev = {"Action": "tap", "Color": 0, "Shape": 0, "Size": 0}
    p = engine.query(["ObjVel"], ev)["ObjVel"] * np.exp(lam * (2 * q - 1) * np.array([-1.0, 0.0, 1.0]))
    p /= p.sum()
    assert np.abs(np.bincount(out["ObjVel"], minlength=3) / n - p).max() < 0.012
    fast = out["ObjVel"] == 2
    want = engine.query(["HandVel"], {**ev, "ObjVel": 2})["HandVel"]
    assert np.abs(np.bincount(out["HandVel"][fast], minlength=2) / fast.sum() - want).max() < 0.02
    grasps, _ = _world(engine, 200, action="grasp")
    same = effects_given_gesture(
        engine, grasps, np.ones(200), GestureEffects(speed_effect=lam), np.random.default_rng(2)
    )
    assert all(np.array_equal(same[k], grasps[k]) for k in grasps)  # only taps by default


def test_the_slowest_taps_fail(engine):
    n = 400
    codes, _ = _world(engine, n)
    q = np.linspace(0, 1, n, endpoint=False)
    out = effects_given_gesture(engine, codes, q, GestureEffects(failed_taps=0.25), np.random.default_rng(3))
    assert (out["ObjVel"][q < 0.25] == 0).all()
    kept = q >= 0.25
    assert all(np.array_equal(out[k][kept], codes[k][kept]) for k in codes)  # the others keep every value
    changed = (codes["ObjVel"] != 0) & ~kept
    assert changed.any()
    words = list(engine.bn.schema.word_nodes)
    assert any((out[w][changed] != codes[w][changed]).any() for w in words)  # words drawn again for them


def test_bad_settings_are_one_line():
    with pytest.raises(DataError, match="speed_effect"):
        GestureEffects(speed_effect=-1)
    with pytest.raises(DataError, match="failed_taps"):
        GestureEffects(failed_taps=1.5)
    with pytest.raises(DataError, match="unknown action 'kick'"):
        GestureEffects(actions=("kick",))
    with pytest.raises(DataError, match="not an effect node"):
        GestureEffects(nodes=("Shape",))
