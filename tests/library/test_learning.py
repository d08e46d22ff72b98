"""Structure and parameter learning against pgmpy's scores and estimators and closed forms (the original:
test_reference)."""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pandas as pd
import pytest

from glu.bn import BayesNet, learn_bn, learn_structure
from glu.bn.learning import bic_family_score, family_counts, k2_parents, learn_parameters
from glu.bn.model import encode
from glu.schema import AFFORDANCE_NODES, ROOT_NODES, WORDS, default_schema

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import pgmpy.structure_score as pgmpy_scores
    from pgmpy.models import DiscreteBayesianNetwork
    from pgmpy.parameter_estimator import DiscreteBayesianEstimator, DiscreteMLE


def _as_strings(df: pd.DataFrame) -> pd.DataFrame:
    return df.astype(str)


def _ours_layout(cpd, parents: tuple[str, ...]) -> np.ndarray:
    """A pgmpy CPD as an array in glu's layout (*parents in the given order, child value)."""
    values = cpd.values  # (child, *evidence) in the order of cpd.variables
    order = [cpd.variables[1:].index(p) + 1 for p in parents]
    return np.transpose(values, [*order, 0])


# ---------------------------------------------------------------- the unseen-row modes
def test_uniform_mode_replaces_exactly_the_zero_rows(table, zero_bn):
    learned_bn = zero_bn
    uni = learn_bn(table, unseen_words="uniform")
    assert uni.edges() == learned_bn.edges()
    assert uni.zero_rows() == {}
    assert learned_bn.zero_rows(), "the faithful model has all-zero rows on this data"
    for node in learned_bn.nodes:
        zero = learned_bn.cpts[node].sum(axis=-1) == 0
        np.testing.assert_array_equal(uni.cpts[node][~zero], learned_bn.cpts[node][~zero])
        assert np.all(uni.cpts[node][zero] == 0.5)


# ---------------------------------------------------------------- against pgmpy
def test_bic_family_scores_equal_pgmpy(table):
    lab_table = table
    schema = default_schema()
    codes = encode(lab_table, schema)
    cards = {n: schema.cardinality(n) for n in schema.nodes}
    data = _as_strings(lab_table)
    names = {n: list(schema.values_of(n)) for n in schema.nodes}
    bic = pgmpy_scores.BIC(data, state_names=names)
    rng = np.random.default_rng(0)
    cases = [
        ("ObjVel", ("Action", "Shape", "Size")),
        ("Contact", ("Action", "Shape", "ObjHandVel")),
        ("but", ()),
    ]
    for _ in range(25):
        child = str(rng.choice(list(AFFORDANCE_NODES[4:]) + list(WORDS)))
        k = int(rng.integers(0, 4))
        parents = tuple(str(p) for p in rng.choice(AFFORDANCE_NODES[:4], size=k, replace=False))
        cases.append((child, parents))
    for child, parents in cases:
        ours = bic_family_score(family_counts(codes, cards, child, parents), len(lab_table))
        ref = bic.local_score(child, parents)
        assert ours == pytest.approx(ref, rel=1e-12, abs=1e-9), (child, parents)


def test_cpts_equal_pgmpy_estimators(table, zero_bn):
    lab_table, learned_bn = table, zero_bn
    schema = learned_bn.schema
    data = _as_strings(lab_table)
    names = {n: list(schema.values_of(n)) for n in schema.nodes}
    model = DiscreteBayesianNetwork()
    model.add_nodes_from(schema.nodes)
    model.add_edges_from(learned_bn.edges())
    est = DiscreteBayesianEstimator(state_names=names, prior_type="BDeu", equivalent_sample_size=1)
    aff_model = DiscreteBayesianNetwork([e for e in learned_bn.edges() if e[1] in AFFORDANCE_NODES])
    aff_model.add_nodes_from(AFFORDANCE_NODES)
    cpds = {c.variable: c for c in est.fit(aff_model, data[list(AFFORDANCE_NODES)]).parameters_}
    for node in AFFORDANCE_NODES:
        theirs = _ours_layout(cpds[node], learned_bn.parents[node])
        np.testing.assert_allclose(theirs, learned_bn.cpts[node], rtol=0, atol=1e-12)
    mle = {c.variable: c for c in DiscreteMLE(state_names=names).fit(model, data).parameters_}
    for word in WORDS:
        ours = learned_bn.cpts[word]
        theirs = _ours_layout(mle[word], learned_bn.parents[word])
        seen = ours.sum(axis=-1) > 0
        np.testing.assert_allclose(theirs[seen], ours[seen], rtol=0, atol=1e-12)
        # unseen configurations: really never observed in the data
        parents = list(learned_bn.parents[word])
        if parents:
            counts = lab_table.groupby(parents, observed=False).size().to_numpy().reshape(seen.shape)
            np.testing.assert_array_equal(counts == 0, ~seen)


# ---------------------------------------------------------------- K2 on closed-form cases
def test_k2_finds_a_deterministic_parent_and_ignores_noise():
    rng = np.random.default_rng(1)
    n = 2000
    a = rng.integers(0, 3, n)
    b = rng.integers(0, 2, n)
    noise = rng.integers(0, 4, n)
    child = (a + (rng.random(n) < 0.05)) % 3  # a copy of a with 5 % errors
    codes = {"a": a, "b": b, "noise": noise, "child": child}
    cards = {"a": 3, "b": 2, "noise": 4, "child": 3}
    assert k2_parents(codes, cards, "child", ["noise", "b", "a"]) == ("a",)
    assert k2_parents(codes, cards, "child", ["noise", "b", "a"], max_parents=0) == ()


def test_k2_brute_force_best_single_parent_matches_first_step():
    """The first K2 step picks the single parent of best BIC (checked against explicit BIC formula)."""
    rng = np.random.default_rng(5)
    n = 500
    cards = {"x": 3, "y": 2, "z": 4, "c": 2}
    codes = {k: rng.integers(0, v, n) for k, v in cards.items() if k != "c"}
    codes["c"] = ((codes["z"] >= 2) ^ (rng.random(n) < 0.3)).astype(int)

    def bic(parents):
        ll = 0.0
        configs = list(itertools.product(*[range(cards[p]) for p in parents]))
        for cfg in configs:
            sel = np.ones(n, bool)
            for p, v in zip(parents, cfg, strict=True):
                sel &= codes[p] == v
            m = sel.sum()
            for v in range(2):
                k = (codes["c"][sel] == v).sum()
                if k:
                    ll += k * np.log(k / m)
        return ll - 0.5 * len(configs) * 1 * np.log(n)

    best = max(["x", "y", "z"], key=lambda p: bic((p,)))
    chosen = k2_parents(codes, cards, "c", ["x", "y", "z"], max_parents=1)
    assert chosen == ((best,) if bic((best,)) > bic(()) else ())
    assert chosen == ("z",)


def test_bdeu_pseudo_counts_closed_form():
    schema = default_schema()
    df = pd.DataFrame(
        {
            n: pd.Categorical([schema.values_of(n)[0]] * 4, categories=schema.values_of(n))
            for n in schema.nodes
        }
    )
    parents = {n: () for n in schema.nodes}
    parents["ObjVel"] = ("Action",)
    cpts = learn_parameters(df, parents, schema)
    # Action: 4 counts of grasp, pseudo-count 1/3 each → (4 + 1/3) / 5
    np.testing.assert_allclose(cpts["Action"], [(4 + 1 / 3) / 5, (1 / 3) / 5, (1 / 3) / 5])
    # ObjVel | Action: row grasp has counts (4, 0, 0) + 1/9 each; unseen rows uniform by the prior
    np.testing.assert_allclose(
        cpts["ObjVel"][0], [(4 + 1 / 9) / (4 + 1 / 3), (1 / 9) / (4 + 1 / 3), (1 / 9) / (4 + 1 / 3)]
    )
    np.testing.assert_allclose(cpts["ObjVel"][1], [1 / 3] * 3)
    # a word: maximum likelihood, no prior
    np.testing.assert_array_equal(cpts["the"], [1.0, 0.0])


def test_learning_is_deterministic_and_saves_round_trip(table, tmp_path):
    a = learn_bn(table)
    b = learn_bn(table)
    assert a.edges() == b.edges()
    for node in ROOT_NODES:  # set by the experimenter: never a parent
        assert a.parents[node] == ()
    p = a.save(tmp_path / "m.json")
    c = BayesNet.load(p)
    for n in a.nodes:
        np.testing.assert_array_equal(a.cpts[n], c.cpts[n])
    assert c.meta["unseen_words"] == "zero"


def test_learn_structure_finds_the_generating_parents():
    """B copies A (5 % errors), C is noise, the word w copies B: K2 gives B ← A and w ← B, A (a root) and C
    nothing; A is not added to w's parents, which B already explains."""
    from glu.schema import Schema

    rng = np.random.default_rng(3)
    n = 3000
    a = rng.integers(0, 3, n)
    b = (a + (rng.random(n) < 0.05)) % 3
    c = rng.integers(0, 2, n)
    df = pd.DataFrame({"A": a, "B": b, "C": c, "w": (b == 0).astype(int)})
    df = df.astype(str).replace({"w": {"0": "absent", "1": "present"}})
    values = {"A": ("0", "1", "2"), "B": ("0", "1", "2"), "C": ("0", "1"), "w": ("absent", "present")}
    schema = Schema(values=values, n_affordance=3, roots=("A",))
    assert learn_structure(df, schema) == {"A": (), "B": ("A",), "C": (), "w": ("B",)}
    assert learn_structure(df, schema, max_parents=0) == {n: () for n in values}


def test_bad_learning_input_is_one_clear_error(table):
    from glu.errors import DataError, ModelError

    with pytest.raises(DataError, match="cannot learn from an empty table"):
        learn_bn(table.iloc[:0])
    with pytest.raises(ModelError, match="unseen_words='drop'; allowed: zero, uniform"):
        learn_parameters(table, {n: () for n in default_schema().nodes}, unseen_words="drop")
