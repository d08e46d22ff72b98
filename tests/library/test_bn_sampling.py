"""Sampling the network: the draws follow the engine's own distribution (faithful zero rows included)."""

from __future__ import annotations

import numpy as np
import pytest

from glu.bn import make_engine
from glu.bn.sampling import categorical, sample
from glu.errors import EvidenceError, UnknownNodeError

N = 60_000


@pytest.fixture(scope="module")
def engine(zero_bn):
    return make_engine(zero_bn)


@pytest.fixture(scope="module")
def draws(engine):
    rng = np.random.default_rng(0)
    fixed = {
        "Action": rng.integers(0, 3, N),
        "Shape": rng.integers(0, 2, N),
        "Size": rng.integers(0, 3, N),
        "Color": rng.integers(0, 4, N),
    }
    return sample(engine, fixed, np.random.default_rng(1))


def test_effects_follow_the_conditional_distribution(engine, draws):
    """Empirical p(X | the four roots) within 4.5 standard errors (plus 3 draws, for rare values) of the
    engine's posterior, for every root combination (the roots are fixed per row: the distribution sampled)."""
    schema = engine.bn.schema
    roots = ("Action", "Color", "Shape", "Size")
    key = np.ravel_multi_index(tuple(draws[r] for r in roots), tuple(schema.cardinality(r) for r in roots))
    for k in np.unique(key):
        rows = key == k
        ev = {
            r: schema.values_of(r)[v]
            for r, v in zip(
                roots, np.unravel_index(k, tuple(schema.cardinality(r) for r in roots)), strict=True
            )
        }
        for node in ("ObjVel", "Contact", "HandVel", "rolls", "taps"):
            p = engine.query(node, ev)[node]
            freq = np.bincount(draws[node][rows], minlength=len(p)) / rows.sum()
            se = np.sqrt(p * (1 - p) / rows.sum())
            assert (np.abs(freq - p) <= 4.5 * se + 3 / rows.sum()).all(), (node, ev, freq, p)


def test_configurations_excluded_by_zero_rows_are_never_drawn(engine, draws):
    """With the original's all-zero word rows, some affordance configurations have probability 0 in every
    query although the affordance CPTs give them mass: they are never drawn."""
    masked = (engine.backend.base == 0) & (engine.backend.prior_joint > 0)
    assert masked.any() == bool(engine.bn.zero_rows())
    drawn = engine.backend.base[tuple(draws[n] for n in engine.backend.core)]
    assert (drawn > 0).all()


def test_fixed_values_are_kept_and_the_draws_are_seeded(engine):
    fixed = {"Action": np.array([0, 1, 2, 1]), "Size": np.array([2, 2, 0, 1])}
    a = sample(engine, fixed, np.random.default_rng(5))
    b = sample(engine, fixed, np.random.default_rng(5))
    assert set(a) == set(engine.nodes)
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert np.array_equal(a["Action"], fixed["Action"]) and np.array_equal(a["Size"], fixed["Size"])


def test_bad_input(engine):
    rng = np.random.default_rng(0)
    with pytest.raises(EvidenceError, match="at least one fixed node"):
        sample(engine, {}, rng)
    with pytest.raises(EvidenceError, match="word"):
        sample(engine, {"rolls": np.zeros(3, int)}, rng)
    with pytest.raises(UnknownNodeError):
        sample(engine, {"Colour": np.zeros(3, int)}, rng)
    with pytest.raises(EvidenceError, match="value indices 0…2"):
        sample(engine, {"Action": np.array([0, 3])}, rng)
    with pytest.raises(EvidenceError, match="different lengths"):
        sample(engine, {"Action": np.zeros(3, int), "Shape": np.zeros(2, int)}, rng)


def test_categorical_is_an_inverse_cdf():
    p = np.array([[0.2, 0.0, 0.8], [0.0, 1.0, 0.0]])
    draws = np.stack([categorical(p, np.random.default_rng(i)) for i in range(2000)])
    assert (draws[:, 1] == 1).all() and not (draws[:, 0] == 1).any()
    assert abs((draws[:, 0] == 0).mean() - 0.2) < 0.04


def test_impossible_fixed_values_and_the_junction_tree_are_refused():
    """B is b0 whatever A is: a row fixing B=b1 has probability 0; a junction-tree engine has no joint."""
    from glu.bn import BayesNet
    from glu.errors import ImpossibleEvidenceError, ModelError
    from glu.schema import Schema

    schema = Schema(values={"A": ("a0", "a1"), "B": ("b0", "b1")}, n_affordance=2)
    cpts = {"A": np.array([0.5, 0.5]), "B": np.array([[1.0, 0.0], [1.0, 0.0]])}
    bn = BayesNet(schema=schema, parents={"A": (), "B": ("A",)}, cpts=cpts)
    rng = np.random.default_rng(0)
    with pytest.raises(
        ImpossibleEvidenceError, match="^row 2: A=a1, B=b1 has probability 0 under the model$"
    ):
        sample(make_engine(bn), {"A": np.array([0, 1, 1]), "B": np.array([0, 0, 1])}, rng)
    with pytest.raises(ModelError, match="answered by the junction tree"):
        sample(make_engine(bn, method="junction"), {"A": np.array([0])}, rng)
