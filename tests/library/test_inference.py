"""Exact inference: against pgmpy's VariableElimination, brute-force enumeration and closed forms."""

from __future__ import annotations

import itertools
import re
import warnings

import numpy as np
import pytest

from glu.bn import BayesNet, make_engine
from glu.errors import EvidenceError, ImpossibleEvidenceError, UnknownNodeError, UnknownValueError
from glu.schema import AFFORDANCE_NODES, WORDS, Schema

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from bn_reference import to_pgmpy, to_pgmpy_with_zero_rows
    from pgmpy.factors.discrete import TabularCPD
    from pgmpy.inference import VariableElimination

TOL = 1e-9


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
    eng = make_engine(uniform_bn)
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


def test_zero_rows_agree_with_pgmpy_and_an_explicit_indicator(zero_bn):
    """The original's all-zero rows: pgmpy with an observed 'seen' indicator per word is the reference."""
    assert zero_bn.zero_rows(), "the faithful model has all-zero rows on this data"
    eng = make_engine(zero_bn)
    model, seen = to_pgmpy_with_zero_rows(zero_bn)
    ve = VariableElimination(model)
    rng = np.random.default_rng(1)
    impossible = 0
    for _ in range(120):
        target, evidence = _random_query(rng, zero_bn)
        if _pgmpy_evidence_probability(ve, {**evidence, **seen}) == 0:
            impossible += 1
            with pytest.raises(ImpossibleEvidenceError, match="impossible evidence"):
                eng.query([target], evidence)
            continue
        ref = _pgmpy_marginal(ve, target, {**evidence, **seen})
        np.testing.assert_allclose(eng.query([target], evidence)[target], ref, rtol=0, atol=TOL)
    assert impossible > 0
    # the mass the zero rows remove: the prior probability of the excluded parent configurations
    ve_uniform = VariableElimination(to_pgmpy(learn_bn_uniform_like(zero_bn)))
    excluded = 0.0
    for word in zero_bn.zero_rows():
        parents = zero_bn.parents[word]
        joint = ve_uniform.query(list(parents), joint=True, show_progress=False)
        rows = zero_bn.cpts[word].sum(axis=-1) == 0
        excluded = max(excluded, float(sum(joint.values[tuple(i)] for i in np.argwhere(rows))))
    assert 1 - eng.probability_of_evidence() >= excluded - 1e-12


def test_virtual_evidence_agrees_with_pgmpy(uniform_bn):
    eng = make_engine(uniform_bn)
    ve = VariableElimination(to_pgmpy(uniform_bn))
    rng = np.random.default_rng(2)
    for _ in range(60):
        target, evidence = _random_query(rng, uniform_bn, max_aff=3, max_words=2)
        free = [n for n in AFFORDANCE_NODES if n not in evidence and n != target]
        soft_node = str(rng.choice(free))
        card = uniform_bn.schema.cardinality(soft_node)
        q = rng.dirichlet(np.ones(card))
        virtual = [
            TabularCPD(
                soft_node,
                card,
                q.reshape(-1, 1),
                state_names={soft_node: list(uniform_bn.schema.values_of(soft_node))},
            )
        ]
        if _pgmpy_evidence_probability(ve, evidence) == 0:
            continue
        ref = _pgmpy_marginal(ve, target, evidence, virtual)
        ours = eng.query([target], evidence, soft={soft_node: q}, soft_rule="virtual")[target]
        np.testing.assert_allclose(ours, ref, rtol=0, atol=TOL)


def test_jeffrey_rule_is_the_mixture_of_hard_posteriors(uniform_bn):
    """Jeffrey: p(X | e, q) = Σ_a p(X | e, A=a) q(a), each term from pgmpy; and the Action marginal becomes
    q."""
    eng = make_engine(uniform_bn)
    ve = VariableElimination(to_pgmpy(uniform_bn))
    q = np.array([0.15, 0.7, 0.15])
    for evidence in (
        {"Shape": "sphere"},
        {"Shape": "box", "Size": "big"},
        {"Size": "small", "is": "present"},
    ):
        for target in ("ObjVel", "Contact", "rolling"):
            ref = sum(
                qa * _pgmpy_marginal(ve, target, {**evidence, "Action": a})
                for a, qa in zip(("grasp", "tap", "touch"), q, strict=True)
            )
            ours = eng.query([target], evidence, soft={"Action": q}, soft_rule="jeffrey")[target]
            np.testing.assert_allclose(ours, ref, rtol=0, atol=TOL)
        post = eng.query(["Action"], evidence, soft={"Action": q}, soft_rule="jeffrey")["Action"]
        np.testing.assert_allclose(post, q, atol=1e-12)


def test_jeffrey_on_two_nodes_fits_both_marginals(uniform_bn):
    eng = make_engine(uniform_bn)
    qa, qs = np.array([0.2, 0.5, 0.3]), np.array([0.6, 0.4])
    post = eng.query(
        ["Action", "Shape"], {"Size": "big"}, soft={"Action": qa, "Shape": qs}, soft_rule="jeffrey"
    )
    np.testing.assert_allclose(post["Action"], qa, atol=1e-10)
    np.testing.assert_allclose(post["Shape"], qs, atol=1e-10)


def test_soft_evidence_certain_equals_hard_evidence(zero_bn):
    eng = make_engine(zero_bn)
    hard = eng.query(["ObjVel", "rolls"], {"Action": "tap", "Shape": "sphere"})
    for rule in ("virtual", "jeffrey"):
        soft = eng.query(
            ["ObjVel", "rolls"], {"Shape": "sphere"}, soft={"Action": {"tap": 1.0}}, soft_rule=rule
        )
        for t in hard:
            np.testing.assert_allclose(soft[t], hard[t], atol=1e-12)


def test_virtual_evidence_on_a_word_agrees_with_pgmpy(uniform_bn):
    """Soft evidence on a leaf (a word) goes to the junction tree; pgmpy's virtual evidence is the
    reference."""
    eng = make_engine(uniform_bn)
    ve = VariableElimination(to_pgmpy(uniform_bn))
    q = np.array([0.3, 0.7])
    virtual = [TabularCPD("rolls", 2, q.reshape(-1, 1), state_names={"rolls": ["absent", "present"]})]
    for evidence in ({"Shape": "sphere"}, {"Action": "tap", "is": "present"}):
        for target in ("ObjVel", "Action", "sliding"):
            if target in evidence:
                continue
            ref = _pgmpy_marginal(ve, target, evidence, virtual)
            np.testing.assert_allclose(
                eng.query([target], evidence, soft={"rolls": q})[target], ref, atol=TOL
            )
    post = eng.query(["rolls"], {"Shape": "sphere"}, soft={"rolls": q}, soft_rule="jeffrey")["rolls"]
    np.testing.assert_allclose(post, q, atol=1e-12)


# ---------------------------------------------------------------- brute force on small random networks
def _tiny_bn(seed: int, zero_rows: bool) -> BayesNet:
    rng = np.random.default_rng(seed)
    values = {
        "A": ("a0", "a1", "a2"),
        "B": ("b0", "b1"),
        "C": ("c0", "c1", "c2"),
        "w1": ("absent", "present"),
        "w2": ("absent", "present"),
        "w3": ("x", "y", "z"),
    }
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
        eng = make_engine(bn)
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


def test_a_tiny_likelihood_on_the_only_possible_value_is_not_called_impossible():
    """Virtual evidence is a likelihood: q and c·q give one posterior, however small q is (log-domain
    safe)."""
    bn = _tiny_bn(0, zero_rows=False)
    bn.cpts["B"][:] = [[1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]  # B=b1 ⇔ A=a2: only a2 is possible given B=b1
    eng = make_engine(bn)
    ref = _brute_force(bn, "C", {"B": "b1"})
    for tiny in (1e-300, 1e-320, 1e-322):
        got = eng.query(["C"], {"B": "b1"}, soft={"A": [0.5, 0.5 - tiny, tiny]})["C"]
        np.testing.assert_allclose(got, ref, atol=1e-12)
    with pytest.raises(ImpossibleEvidenceError, match="the hard evidence alone is possible"):
        eng.query(["C"], {"B": "b1"}, soft={"A": [0.5, 0.5, 0.0]})


@pytest.mark.parametrize(
    ("soft", "message"),
    [
        (["a", "b", "c"], "must be a list of 3 numbers"),
        ([[1], [0], [0]], "must be a flat list"),
        ({"a0": "x"}, "the probability of 'a0' must be a number, got 'x'"),
        ({"a0": [1]}, "must be a number"),
        ({"a0": True}, "must be a number"),
        ("abc", "must be a list of 3 numbers"),
        ([0.5, 0.5], "has 2 entries"),
    ],
)
def test_malformed_soft_evidence_is_one_clear_error(soft, message):
    eng = make_engine(_tiny_bn(1, zero_rows=False))
    with pytest.raises(EvidenceError, match=re.escape(message)):
        eng.query(["C"], soft={"A": soft})


# ---------------------------------------------------------------- batch and word fast paths
def test_word_probabilities_equal_single_queries(zero_bn):
    eng = make_engine(zero_bn)
    for evidence in (
        {},
        {"Size": "big", "Shape": "sphere", "ObjVel": "fast"},
        {"Action": "tap", "rolls": "present"},
    ):
        probs = eng.word_probability_array(evidence)
        assert probs.shape == (49,)
        for i, w in enumerate(eng.binary_leaves):
            assert probs[i] == pytest.approx(eng.query([w], evidence)[w][1], abs=1e-12)


def test_batch_equals_single_queries(zero_bn):
    eng = make_engine(zero_bn)
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
def test_batch_soft_evidence_equals_single_queries(zero_bn, rule):
    eng = make_engine(zero_bn)
    rng = np.random.default_rng(5)
    n = 50
    q = rng.dirichlet(np.ones(3), size=n)
    shape = [str(rng.choice(["sphere", "box"])) for _ in range(n)]
    out = eng.query_batch(["ObjVel", "rolls"], {"Shape": shape}, soft={"Action": q}, soft_rule=rule)
    for i in range(n):
        single = eng.query(["ObjVel", "rolls"], {"Shape": shape[i]}, soft={"Action": q[i]}, soft_rule=rule)
        for t in single:
            np.testing.assert_allclose(out[t][i], single[t], atol=1e-12)


def test_batch_raises_on_impossible_rows_by_default(zero_bn):
    eng = make_engine(zero_bn)
    word, parents, row = _a_zero_row(zero_bn)
    possible = _a_possible_row(zero_bn, parents)
    ev = {p: [possible[i], row[i]] for i, p in enumerate(parents)}
    with pytest.raises(ImpossibleEvidenceError, match="row 1"):
        eng.query_batch(["Action"], ev)
    out = eng.query_batch(["Action"], ev, errors="nan")
    assert np.isfinite(out["Action"][0]).all() and np.isnan(out["Action"][1]).all()


@pytest.mark.parametrize("method", ["core", "junction"])
def test_bad_batch_soft_evidence_is_one_clear_error_on_both_engines(zero_bn, method):
    eng = make_engine(zero_bn, method=method)
    shapes = {"Shape": ["sphere", "box"]}
    with pytest.raises(UnknownNodeError, match=r"unknown node 'Colour'"):
        eng.query_batch(["ObjVel"], shapes, soft={"Colour": np.full((2, 2), 0.5)})
    with pytest.raises(EvidenceError, match="given twice"):
        eng.query_batch(["ObjVel"], shapes, soft={"Shape": np.full((2, 2), 0.5)})
    with pytest.raises(EvidenceError, match=r"must have shape \(n=2, n_values\)"):
        eng.query_batch(["ObjVel"], shapes, soft={"Action": np.full((2, 3, 1), 1 / 3)})
    with pytest.raises(EvidenceError, match="not a distribution"):
        eng.query_batch(["ObjVel"], shapes, soft={"Action": np.array([[0.5, 0.5, 0.0], [-0.1, 1.1, 0.0]])})


# ---------------------------------------------------------------- errors
def test_errors_are_clear_value_errors(zero_bn):
    eng = make_engine(zero_bn)
    with pytest.raises(UnknownNodeError, match=r"unknown node 'Colour' \(did you mean Color\?\)"):
        eng.query(["Colour"])
    with pytest.raises(UnknownValueError, match=r"Shape has no value 'ball'; allowed: sphere, box"):
        eng.query(["ObjVel"], {"Shape": "ball"})
    assert eng.query(["ObjVel"], {"Shape": "circle"})["ObjVel"] == pytest.approx(
        eng.query(["ObjVel"], {"Shape": "sphere"})["ObjVel"]
    )
    with pytest.raises(EvidenceError, match="given twice"):
        eng.query(["ObjVel"], {"Action": "tap"}, soft={"Action": [0, 1, 0]})
    with pytest.raises(EvidenceError, match="not a distribution"):
        eng.query(["ObjVel"], soft={"Action": [0.5, 0.6, 0.0]})
    with pytest.raises(EvidenceError, match="not a distribution"):
        eng.query(["ObjVel"], soft={"Action": [-0.5, 1.5, 0.0]})
    with pytest.raises(EvidenceError, match="3 entries; expected 2"):
        eng.query(["ObjVel"], soft={"Shape": [0.2, 0.3, 0.5]})
    for err in (UnknownNodeError, UnknownValueError, EvidenceError, ImpossibleEvidenceError):
        assert issubclass(err, ValueError)


# ---------------------------------------------------------------- helpers
def learn_bn_uniform_like(bn: BayesNet) -> BayesNet:
    """``bn`` with every all-zero row made uniform (the prior over affordance configurations, unexcluded)."""
    cpts = {}
    for n in bn.nodes:
        c = bn.cpts[n].copy()
        c[c.sum(axis=-1) == 0] = 1.0 / c.shape[-1]
        cpts[n] = c
    return BayesNet(schema=bn.schema, parents=bn.parents, cpts=cpts)


def _a_zero_row(bn: BayesNet) -> tuple[str, tuple[str, ...], tuple[str, ...]]:
    """A word with an all-zero row, its parents, and the parents' values on that row."""
    word = sorted(bn.zero_rows())[0]
    parents = bn.parents[word]
    idx = np.argwhere(bn.cpts[word].sum(axis=-1) == 0)[0]
    return word, parents, tuple(bn.schema.values_of(p)[i] for p, i in zip(parents, idx, strict=True))


def _a_possible_row(bn: BayesNet, parents: tuple[str, ...]) -> tuple[str, ...]:
    """Values of ``parents`` that no zero row excludes and that have prior probability > 0."""
    eng = make_engine(bn)
    for combo in itertools.product(*[bn.schema.values_of(p) for p in parents]):
        if eng.probability_of_evidence(dict(zip(parents, combo, strict=True))) > 0:
            return combo
    raise AssertionError("no possible configuration")


def test_unknown_soft_rule_and_malformed_batches_are_one_clear_error():
    eng = make_engine(_tiny_bn(1, zero_rows=False))
    with pytest.raises(EvidenceError, match="^unknown soft rule 'bayes'; allowed: virtual, jeffrey$"):
        eng.query(["C"], soft={"A": [0.2, 0.3, 0.5]}, soft_rule="bayes")
    with pytest.raises(EvidenceError, match=r"batch evidence columns have different lengths: \[2, 3\]"):
        eng.query_batch(["C"], {"A": ["a0", "a1"], "B": ["b0", "b1", "b0"]})
    with pytest.raises(
        EvidenceError, match="a batch query needs at least one evidence or soft-evidence column"
    ):
        eng.query_batch(["C"], {})
    with pytest.raises(UnknownValueError, match="B has no value '2'; allowed: b0, b1"):
        eng.query_batch(["C"], {"B": np.array([0, 2, 1])})


def test_numpy_scalars_are_value_indices_and_names():
    from glu.bn.parse import Values

    vals = Values(_tiny_bn(1, zero_rows=False))
    assert vals.value("A", np.int64(2)) == 2 and type(vals.value("A", np.int64(2))) is int
    assert vals.value("A", np.str_("a1")) == 1
    with pytest.raises(UnknownValueError, match="A has no value '3'"):
        vals.value("A", np.uint8(3))


def test_a_network_without_words_has_no_word_probabilities():
    bn = _tiny_bn(1, zero_rows=False)
    schema = Schema(values={n: bn.schema.values_of(n) for n in ("A", "B", "C")}, n_affordance=3)
    bare = BayesNet(
        schema=schema, parents={n: bn.parents[n] for n in "ABC"}, cpts={n: bn.cpts[n] for n in "ABC"}
    )
    assert make_engine(bare).word_probability_array({"A": "a1"}).shape == (0,)


@pytest.mark.parametrize("method", ["core", "junction"])
def test_answers_stay_exact_when_the_caches_start_again_and_batches_are_cut(monkeypatch, method):
    """Caches of one entry (every pattern and every evidence set evicts the last) and batches cut into
    rows of one: every answer still equals brute force."""
    from glu.bn import inference

    monkeypatch.setattr(inference, "PATTERN_CACHE", 1)
    monkeypatch.setattr(inference, "POSSIBLE_MEMO", 1)
    monkeypatch.setattr(inference, "BATCH_ENTRIES", 1)
    zero_in_b = _tiny_bn(2, zero_rows=False)
    zero_in_b.cpts["B"][0] = [1.0, 0.0]  # B = b0 whenever A = a0
    cases = [({"B": "b1"}, "A"), ({"C": "c2"}, "w1"), ({"B": "b1"}, "B"), ({"w3": "y", "A": "a0"}, "B")]
    for bn in (zero_in_b, _tiny_bn(2, zero_rows=True)):
        eng = make_engine(bn, method=method)
        for evidence, target in cases * 2:
            ref = _brute_force(bn, target, evidence)
            if ref is None:
                with pytest.raises(ImpossibleEvidenceError):
                    eng.query([target], evidence)
            else:
                np.testing.assert_allclose(eng.query([target], evidence)[target], ref, atol=1e-12)
    column = ["b0", "b1", "b1", "b0", "b1"]
    out = eng.query_batch(["C", "w1"], {"B": column}, errors="nan")
    for i, b in enumerate(column):
        for t in ("C", "w1"):
            np.testing.assert_allclose(out[t][i], _brute_force(bn, t, {"B": b}), atol=1e-12)


def test_labelled_answers_without_pandas_block_constructor(monkeypatch):
    """A pandas without ``SingleBlockManager`` (the fast constructor): Series made by ``pd.Series``. (The
    module is not reloaded: a second ``Labels`` class would no longer pickle.)"""
    import pandas as pd
    import pandas.core.internals

    from glu.bn import labels

    monkeypatch.delattr(pandas.core.internals, "SingleBlockManager")
    assert labels._from_blocks() is None
    monkeypatch.setattr(labels, "_make", labels._public)
    s = labels.series(np.array([0.25, 0.75]), pd.Index(["no", "yes"], name="Rain"), "Rain")
    assert s.to_dict() == {"no": 0.25, "yes": 0.75} and s.name == "Rain" and s.index.name == "Rain"
