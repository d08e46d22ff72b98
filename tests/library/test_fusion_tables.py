"""The closed-form fusion over network tables equals fuse() on the engine (synthetic and real data)."""

from __future__ import annotations

import numpy as np
import pytest

from glu.bn import make_engine
from glu.errors import EvidenceError
from glu.fusion import STRATEGIES, fuse, fuse_action_tables, fuse_tables

ACTIONS = ("grasp", "tap", "touch")
EVIDENCE = [{"Shape": "sphere", "Size": "small"}, {"Shape": "box", "ObjVel": "medium"}, {"Color": "yellow"}]


@pytest.fixture(scope="module")
def engine(zero_bn):
    return make_engine(zero_bn)


def tables(engine, evidence, target):
    p_a = engine.query(["Action"], evidence)["Action"]
    if target == "words":
        p_x = np.stack([engine.word_probability_array({**evidence, "Action": a}) for a in ACTIONS])
    else:
        p_x = np.stack([engine.query([target], {**evidence, "Action": a})[target] for a in ACTIONS])
    return p_a, p_x


@pytest.mark.parametrize("evidence", EVIDENCE)
@pytest.mark.parametrize("strategy", ["hard", "virtual", "jeffrey"])
def test_effect_and_words_equal_fuse(engine, evidence, strategy):
    q = np.random.default_rng(0).dirichlet(np.ones(3), size=6)  # (T, K)
    for target in ("ObjVel", "Contact"):
        p_a, p_x = tables(engine, evidence, target)
        np.testing.assert_allclose(
            fuse_tables(p_x, p_a, q, strategy),
            fuse(engine, target, evidence, q, strategy)[target],
            atol=1e-12,
        )
    p_a, p_w = tables(engine, evidence, "words")
    for t in range(len(q)):
        soft = {} if strategy == "hard" else {"Action": q[t]}
        ev = {**evidence, "Action": ACTIONS[int(np.argmax(q[t]))]} if strategy == "hard" else evidence
        ref = engine.word_probability_array(ev, soft or None, "virtual" if strategy == "hard" else strategy)
        np.testing.assert_allclose(fuse_tables(p_w, p_a, q[t], strategy), ref, atol=1e-12)


@pytest.mark.parametrize("evidence", EVIDENCE)
@pytest.mark.parametrize("strategy", STRATEGIES)
def test_action_equals_fuse(engine, evidence, strategy):
    q = np.random.default_rng(1).dirichlet(np.ones(3), size=5)
    p_a = engine.query(["Action"], evidence)["Action"]
    np.testing.assert_allclose(
        fuse_action_tables(p_a, q, strategy),
        fuse(engine, "Action", evidence, q, strategy)["Action"],
        atol=1e-12,
    )


def test_the_action_identities():
    """For Action itself: virtual evidence is the product rule; Jeffrey's rule returns p_HMM."""
    rng = np.random.default_rng(2)
    p_a, q = rng.dirichlet(np.ones(3), size=(2, 7))
    np.testing.assert_allclose(fuse_action_tables(p_a, q, "virtual"), fuse_action_tables(p_a, q, "product"))
    np.testing.assert_allclose(fuse_action_tables(p_a, q, "jeffrey"), q)
    p_a[:, 0] = 0.0  # an action the evidence rules out: Jeffrey's rule on the others
    np.testing.assert_allclose(
        fuse_action_tables(p_a, q, "jeffrey"), q * [0, 1, 1] / (q * [0, 1, 1]).sum(1, keepdims=True)
    )
    hard = fuse_action_tables(p_a, q, "hard")
    assert (hard.sum(axis=1) == 1).all() and (hard.argmax(axis=1) == q.argmax(axis=1)).all()


def test_leading_axes_broadcast_and_errors():
    rng = np.random.default_rng(3)
    p_x = rng.dirichlet(np.ones(4), size=(5, 3))  # (n, K, V)
    p_a = rng.dirichlet(np.ones(3), size=5)  # (n, K)
    q = rng.dirichlet(np.ones(3), size=(5, 2))  # (n, F, K)
    out = fuse_tables(p_x[:, None], p_a[:, None], q, "virtual")
    assert out.shape == (5, 2, 4)
    np.testing.assert_allclose(out[3, 1], fuse_tables(p_x[3], p_a[3], q[3, 1], "virtual"))
    with pytest.raises(EvidenceError, match="product rule"):
        fuse_tables(p_x, p_a, q[:, 0], "product")
    assert np.isnan(fuse_action_tables([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], "virtual")).all()
