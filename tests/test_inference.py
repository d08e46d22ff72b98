"""Exact inference: against pgmpy's VariableElimination, brute-force enumeration and closed forms."""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest

from glu.bn import BayesNet, InferenceEngine, learn_bn
from glu.errors import EvidenceError, ImpossibleEvidenceError, UnknownNodeError, UnknownValueError
from glu.schema import AFFORDANCE_NODES, WORDS, Schema

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from pgmpy.factors.discrete import TabularCPD
    from pgmpy.inference import VariableElimination

    from glu.bn.pgmpy_bridge import to_pgmpy, to_pgmpy_with_zero_rows

TOL = 1e-9


@pytest.fixture(scope="module")
def uniform_bn(lab_table):
    return learn_bn(lab_table, unseen_words="uniform")


def _random_query(rng, bn: BayesNet, max_aff=4, max_words=3):
    aff = list(rng.choice(AFFORDANCE_NODES, size=int(rng.integers(0, max_aff + 1)), replace=False))
    words = list(rng.choice(WORDS, size=int(rng.integers(0, max_words + 1)), replace=False))
    evidence = {str(n): str(rng.choice(bn.schema.values_of(str(n)))) for n in aff + words}
    pool = [n for n in bn.nodes if n not in evidence]
    target = str(rng.choice(pool))
    return target, evidence


def _pgmpy_evidence_probability(ve, evidence: dict) -> float:
    """P(evidence) from pgmpy's joint over the evidence nodes (pgmpy does not flag impossible evidence)."""
    if not evidence:
        return 1.0
    joint = ve.query(list(evidence), joint=True, show_progress=False)
    return float(joint.get_value(**evidence))


def _pgmpy_marginal(ve, target, evidence, virtual=None):
    q = ve.query([target], evidence=evidence, virtual_evidence=virtual, show_progress=False)
    return q.values


def test_hard_evidence_agrees_with_pgmpy(uniform_bn):
    eng = InferenceEngine(uniform_bn)
    ve = VariableElimination(to_pgmpy(uniform_bn))
    rng = np.random.default_rng(0)
    checked = 0
    for _ in range(250):
        target, evidence = _random_query(rng, uniform_bn)
        if _pgmpy_evidence_probability(ve, evidence) == 0:
            with pytest.raises(ImpossibleEvidenceError):
                eng.query([target], evidence)
            continue
        ref = _pgmpy_marginal(ve, target, evidence)
        np.testing.assert_allclose(eng.query([target], evidence)[target], ref, rtol=0, atol=TOL)
        checked += 1
    assert checked > 200


def test_zero_rows_agree_with_pgmpy_and_an_explicit_indicator(original_bn):
    """The original's all-zero rows: pgmpy with an observed 'seen' indicator per word is the reference."""
    eng = InferenceEngine(original_bn)
    model, seen = to_pgmpy_with_zero_rows(original_bn)
    ve = VariableElimination(model)
    rng = np.random.default_rng(1)
    impossible = 0
    for _ in range(120):
        target, evidence = _random_query(rng, original_bn)
        if _pgmpy_evidence_probability(ve, {**evidence, **seen}) == 0:
            impossible += 1
            with pytest.raises(ImpossibleEvidenceError, match="impossible evidence"):
                eng.query([target], evidence)
            continue
        ref = _pgmpy_marginal(ve, target, {**evidence, **seen})
        np.testing.assert_allclose(eng.query([target], evidence)[target], ref, rtol=0, atol=TOL)
    assert impossible > 0
    # the configurations the quirk removes are impossible evidence
    with pytest.raises(ImpossibleEvidenceError, match="ObjVel=fast, HandVel=fast, Contact=short"):
        eng.query(["Action"], {"ObjVel": "fast", "HandVel": "fast", "Contact": "short"})
    assert eng.base_mass == pytest.approx(1 - 0.0165, abs=5e-4)  # 1.65 % of the prior mass disappears


def test_virtual_evidence_agrees_with_pgmpy(uniform_bn):
    eng = InferenceEngine(uniform_bn)
    ve = VariableElimination(to_pgmpy(uniform_bn))
    rng = np.random.default_rng(2)
    for _ in range(60):
        target, evidence = _random_query(rng, uniform_bn, max_aff=3, max_words=2)
        free = [n for n in AFFORDANCE_NODES if n not in evidence and n != target]
        soft_node = str(rng.choice(free))
        card = uniform_bn.schema.cardinality(soft_node)
        q = rng.dirichlet(np.ones(card))
        virtual = [TabularCPD(soft_node, card, q.reshape(-1, 1),
                              state_names={soft_node: list(uniform_bn.schema.values_of(soft_node))})]  # fmt: skip
        if _pgmpy_evidence_probability(ve, evidence) == 0:
            continue
        ref = _pgmpy_marginal(ve, target, evidence, virtual)
        ours = eng.query([target], evidence, soft={soft_node: q}, soft_rule="virtual")[target]
        np.testing.assert_allclose(ours, ref, rtol=0, atol=TOL)


def test_jeffrey_rule_is_the_mixture_of_hard_posteriors(uniform_bn):
    """Jeffrey: p(X | e, q) = Σ_a p(X | e, A=a) q(a), each term from pgmpy; and the Action marginal becomes q."""
    eng = InferenceEngine(uniform_bn)
    ve = VariableElimination(to_pgmpy(uniform_bn))
    q = np.array([0.15, 0.7, 0.15])
    for evidence in (
        {"Shape": "sphere"},
        {"Shape": "box", "Size": "big"},
        {"Size": "small", "is": "present"},
    ):
        for target in ("ObjVel", "Contact", "rolling"):
            ref = sum(qa * _pgmpy_marginal(ve, target, {**evidence, "Action": a})
                      for a, qa in zip(("grasp", "tap", "touch"), q, strict=True))  # fmt: skip
            ours = eng.query([target], evidence, soft={"Action": q}, soft_rule="jeffrey")[target]
            np.testing.assert_allclose(ours, ref, rtol=0, atol=TOL)
        post = eng.query(["Action"], evidence, soft={"Action": q}, soft_rule="jeffrey")["Action"]
        np.testing.assert_allclose(post, q, atol=1e-12)


def test_jeffrey_on_two_nodes_fits_both_marginals(uniform_bn):
    eng = InferenceEngine(uniform_bn)
    qa, qs = np.array([0.2, 0.5, 0.3]), np.array([0.6, 0.4])
    post = eng.query(
        ["Action", "Shape"], {"Size": "big"}, soft={"Action": qa, "Shape": qs}, soft_rule="jeffrey"
    )
    np.testing.assert_allclose(post["Action"], qa, atol=1e-10)
    np.testing.assert_allclose(post["Shape"], qs, atol=1e-10)


def test_soft_evidence_certain_equals_hard_evidence(original_bn):
    eng = InferenceEngine(original_bn)
    hard = eng.query(["ObjVel", "rolls"], {"Action": "tap", "Shape": "sphere"})
    for rule in ("virtual", "jeffrey"):
        soft = eng.query(
            ["ObjVel", "rolls"], {"Shape": "sphere"}, soft={"Action": {"tap": 1.0}}, soft_rule=rule
        )
        for t in hard:
            np.testing.assert_allclose(soft[t], hard[t], atol=1e-12)


# ---------------------------------------------------------------- brute force on small random networks
def _tiny_bn(seed: int, zero_rows: bool) -> BayesNet:
    rng = np.random.default_rng(seed)
    values = {"A": ("a0", "a1", "a2"), "B": ("b0", "b1"), "C": ("c0", "c1", "c2"),
              "w1": ("absent", "present"), "w2": ("absent", "present"), "w3": ("x", "y", "z")}  # fmt: skip
    schema = Schema(values=values, n_affordance=3)
    parents = {"A": (), "B": ("A",), "C": ("A", "B"), "w1": ("B", "C"), "w2": (), "w3": ("A", "C")}
    cpts = {}
    for n, ps in parents.items():
        shape = tuple(len(values[p]) for p in ps) + (len(values[n]),)
        cpt = rng.dirichlet(np.ones(shape[-1]), size=shape[:-1]) if ps else rng.dirichlet(np.ones(shape[-1]))
        cpts[n] = cpt.reshape(shape)
    if zero_rows:
        cpts["w1"][1, 2] = 0.0
        cpts["w3"][0, 1] = 0.0
    return BayesNet(schema=schema, parents=parents, cpts=cpts)


def _brute_force(bn: BayesNet, target: str, evidence: dict, virtual: dict | None = None) -> np.ndarray | None:
    nodes = bn.nodes
    card = [bn.schema.cardinality(n) for n in nodes]
    out = np.zeros(bn.schema.cardinality(target))
    for states in itertools.product(*[range(c) for c in card]):
        s = dict(zip(nodes, states, strict=True))
        if any(s[n] != bn.schema.values_of(n).index(v) for n, v in evidence.items()):
            continue
        p = 1.0
        for n in nodes:
            p *= bn.cpts[n][tuple(s[q] for q in bn.parents[n]) + (s[n],)]
        for n, lik in (virtual or {}).items():
            p *= lik[s[n]]
        out[s[target]] += p
    return None if out.sum() == 0 else out / out.sum()


@pytest.mark.parametrize("zero_rows", [False, True])
def test_brute_force_on_tiny_networks(zero_rows):
    rng = np.random.default_rng(3)
    for seed in range(4):
        bn = _tiny_bn(seed, zero_rows)
        eng = InferenceEngine(bn)
        for _ in range(40):
            k = int(rng.integers(0, 4))
            ev_nodes = list(rng.choice(bn.nodes, size=k, replace=False))
            evidence = {str(n): str(rng.choice(bn.schema.values_of(str(n)))) for n in ev_nodes}
            target = str(rng.choice([n for n in bn.nodes if n not in evidence]))
            free_core = [n for n in ("A", "B", "C") if n not in evidence]
            virtual = {}
            if free_core and rng.random() < 0.5:
                v = str(rng.choice(free_core))
                virtual[v] = rng.dirichlet(np.ones(bn.schema.cardinality(v)))
            ref = _brute_force(bn, target, evidence, virtual)
            if ref is None:
                with pytest.raises(ImpossibleEvidenceError):
                    eng.query([target], evidence, soft=virtual or None)
                continue
            np.testing.assert_allclose(
                eng.query([target], evidence, soft=virtual or None)[target], ref, atol=1e-12
            )


# ---------------------------------------------------------------- batch and word fast paths
def test_word_probabilities_equal_single_queries(original_bn):
    eng = InferenceEngine(original_bn)
    for evidence in (
        {},
        {"Size": "big", "Shape": "sphere", "ObjVel": "fast"},
        {"Action": "tap", "rolls": "present"},
    ):
        probs = eng.word_probabilities(evidence)
        assert probs.shape == (49,)
        for i, w in enumerate(eng.binary_leaves):
            assert probs[i] == pytest.approx(eng.query([w], evidence)[w][1], abs=1e-12)


def test_batch_equals_single_queries(original_bn):
    eng = InferenceEngine(original_bn)
    rng = np.random.default_rng(4)
    n = 300
    evidence = {
        "Action": [
            str(rng.choice(["grasp", "tap", "touch"])) if rng.random() < 0.8 else None for _ in range(n)
        ],
        "Size": [str(rng.choice(["small", "medium", "big"])) for _ in range(n)],
        "rolls": [str(rng.choice(["absent", "present"])) if rng.random() < 0.5 else None for _ in range(n)],
        "Contact": [str(rng.choice(["short", "long"])) if rng.random() < 0.3 else None for _ in range(n)],
    }
    targets = ["ObjVel", "Action", "sliding", "rolls"]
    out = eng.query_batch(targets, evidence, errors="nan")
    for i in range(n):
        ev = {k: v[i] for k, v in evidence.items() if v[i] is not None}
        try:
            single = eng.query(targets, ev)
        except ImpossibleEvidenceError:
            assert np.isnan(out["ObjVel"][i]).all()
            continue
        for t in targets:
            np.testing.assert_allclose(out[t][i], single[t], atol=1e-12)


@pytest.mark.parametrize("rule", ["virtual", "jeffrey"])
def test_batch_soft_evidence_equals_single_queries(original_bn, rule):
    eng = InferenceEngine(original_bn)
    rng = np.random.default_rng(5)
    n = 50
    q = rng.dirichlet(np.ones(3), size=n)
    shape = [str(rng.choice(["sphere", "box"])) for _ in range(n)]
    out = eng.query_batch(["ObjVel", "rolls"], {"Shape": shape}, soft={"Action": q}, soft_rule=rule)
    for i in range(n):
        single = eng.query(["ObjVel", "rolls"], {"Shape": shape[i]}, soft={"Action": q[i]}, soft_rule=rule)
        for t in single:
            np.testing.assert_allclose(out[t][i], single[t], atol=1e-12)


def test_batch_raises_on_impossible_rows_by_default(original_bn):
    eng = InferenceEngine(original_bn)
    ev = {"ObjVel": ["slow", "fast"], "HandVel": ["slow", "fast"], "Contact": ["long", "short"]}
    with pytest.raises(ImpossibleEvidenceError, match="row 1"):
        eng.query_batch(["Action"], ev)


# ---------------------------------------------------------------- errors
def test_errors_are_clear_value_errors(original_bn):
    eng = InferenceEngine(original_bn)
    with pytest.raises(UnknownNodeError, match=r"unknown node 'Colour' \(did you mean Color\?\)"):
        eng.query(["Colour"])
    with pytest.raises(UnknownValueError, match=r"Shape has no value 'ball'; allowed: sphere, box"):
        eng.query(["ObjVel"], {"Shape": "ball"})
    assert eng.query(["ObjVel"], {"Shape": "circle"})["ObjVel"] == pytest.approx(
        eng.query(["ObjVel"], {"Shape": "sphere"})["ObjVel"])  # fmt: skip
    with pytest.raises(EvidenceError, match="given twice"):
        eng.query(["ObjVel"], {"Action": "tap"}, soft={"Action": [0, 1, 0]})
    with pytest.raises(EvidenceError, match="not a distribution"):
        eng.query(["ObjVel"], soft={"Action": [0.5, 0.6, 0.0]})
    with pytest.raises(EvidenceError, match="not a distribution"):
        eng.query(["ObjVel"], soft={"Action": [-0.5, 1.5, 0.0]})
    with pytest.raises(EvidenceError, match="3 entries; expected 2"):
        eng.query(["ObjVel"], soft={"Shape": [0.2, 0.3, 0.5]})
    with pytest.raises(EvidenceError, match="word node"):
        eng.query(["ObjVel"], soft={"rolls": [0.5, 0.5]})
    for err in (UnknownNodeError, UnknownValueError, EvidenceError, ImpossibleEvidenceError):
        assert issubclass(err, ValueError)


# ---------------------------------------------------------------- the paper's numbers
def test_glu2017_effect_prediction_equals_the_original_model(learned_bn, original_bn):
    ours = InferenceEngine(learned_bn)
    orig = InferenceEngine(original_bn)
    model, seen = to_pgmpy_with_zero_rows(original_bn)
    ve = VariableElimination(model)
    for ev in (
        {"Action": "tap", "Shape": "sphere", "Size": "small"},
        {"Action": "tap", "Shape": "box", "Size": "big"},
    ):
        a = ours.query(["ObjVel"], ev)["ObjVel"]
        np.testing.assert_allclose(a, orig.query(["ObjVel"], ev)["ObjVel"], atol=1e-6)
        np.testing.assert_allclose(a, _pgmpy_marginal(ve, "ObjVel", {**ev, **seen}), atol=1e-9)
    sphere = ours.query(["ObjVel"], {"Action": "tap", "Shape": "sphere", "Size": "small"})["ObjVel"]
    box = ours.query(["ObjVel"], {"Action": "tap", "Shape": "box", "Size": "big"})["ObjVel"]
    assert sphere.argmax() == 2 and box.argmax() == 0  # the sphere rolls fast, the box barely moves
