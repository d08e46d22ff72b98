"""The junction tree engine beyond plain marginals: Jeffrey's rule, tiny likelihoods, both batch plans,
the probability of evidence, GLU's own network, and the size limit (one line, never an internal error).

References: pyAgrum (hard and likelihood evidence), pgmpy, brute-force enumeration, the core engine
(an independent implementation on the joint table), closed forms.
"""

from __future__ import annotations

import itertools
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from glu.bn import BayesNet, Engine, make_engine
from glu.bn.plan import MAX_TABLE_ENV, max_table_setting, plan_junction_tree
from glu.errors import EvidenceError, ImpossibleEvidenceError, ModelError
from glu.schema import Schema

gum = pytest.importorskip("pyagrum")


def chain_net(n: int, card: int, seed: int, extra_parents: int = 0) -> BayesNet:
    """A random network: node i's parents are up to ``1 + extra_parents`` of the nodes before it (seeded)."""
    rng = np.random.default_rng(seed)
    names = [f"X{i}" for i in range(n)]
    values = {x: tuple(f"v{k}" for k in range(card)) for x in names}
    parents = {}
    for i, x in enumerate(names):
        k = min(i, 1 + extra_parents)
        parents[x] = tuple(sorted((names[j] for j in rng.choice(i, size=k, replace=False)), key=names.index))
    cpts = {
        x: rng.dirichlet(np.ones(card), size=tuple(card for _ in parents[x])).reshape(
            *(card for _ in parents[x]), card
        )
        for x in names
    }
    return BayesNet(schema=Schema(values=values, n_affordance=n), parents=parents, cpts=cpts)


def brute_force(bn: BayesNet, target: str, hard: dict, likelihood: dict | None = None) -> np.ndarray | None:
    nodes = bn.nodes
    out = np.zeros(bn.schema.cardinality(target))
    for states in itertools.product(*[range(bn.schema.cardinality(n)) for n in nodes]):
        s = dict(zip(nodes, states, strict=True))
        if any(s[n] != v for n, v in hard.items()):
            continue
        p = 1.0
        for n in nodes:
            p *= bn.cpts[n][tuple(s[q] for q in bn.parents[n]) + (s[n],)]
        for n, lik in (likelihood or {}).items():
            p *= lik[s[n]]
        out[s[target]] += p
    return None if out.sum() == 0 else out / out.sum()


# ---------------------------------------------------------------- evidence types
def test_engines_are_chosen_by_shape():
    small, large = chain_net(6, 2, 0), chain_net(30, 3, 0, extra_parents=2)
    assert make_engine(small).method == "core"
    assert make_engine(large).method == "junction"
    assert make_engine(small, method="junction").method == "junction"
    assert all(isinstance(e, Engine) for e in (make_engine(small), make_engine(large)))
    with pytest.raises(ModelError, match="unknown inference method 'fast'"):
        make_engine(small, method="fast")


def test_virtual_and_hard_evidence_against_brute_force():
    bn = chain_net(7, 3, 1, extra_parents=1)
    eng = make_engine(bn, method="junction")
    rng = np.random.default_rng(0)
    for _ in range(40):
        nodes = list(rng.choice(bn.nodes, size=3, replace=False))
        hard = {str(nodes[0]): int(rng.integers(3))}
        lik = {str(nodes[1]): rng.dirichlet(np.ones(3))}
        target = str(nodes[2])
        ref = brute_force(bn, target, hard, lik)
        np.testing.assert_allclose(eng.query([target], hard, soft=lik)[target], ref, atol=1e-12)


def test_jeffrey_on_one_node_is_the_mixture_of_pyagrum_posteriors(tmp_path):
    """Jeffrey: p(X | e, q) = Σ_a p(X | e, A=a) q(a), each term from pyAgrum."""
    from glu.bn.exchange import to_xmlbif

    bn = chain_net(25, 3, 2, extra_parents=2)
    path = tmp_path / "net.bifxml"
    path.write_text(to_xmlbif(bn))
    ie = gum.LazyPropagation(gum.loadBN(str(path)))
    eng = make_engine(bn)
    assert eng.method == "junction"
    q = np.array([0.2, 0.5, 0.3])
    hard = {"X20": 1}
    ours = eng.query(list(bn.nodes), hard, soft={"X7": q}, soft_rule="jeffrey")
    ref = {n: np.zeros(3) for n in bn.nodes}
    for a, qa in enumerate(q):
        ie.eraseAllEvidence()
        ie.setEvidence({**hard, "X7": a})
        ie.makeInference()
        for n in bn.nodes:
            ref[n] += qa * ie.posterior(n).toarray()
    for n in bn.nodes:
        np.testing.assert_allclose(ours[n], ref[n], atol=1e-12)


def test_jeffrey_on_several_nodes_fits_every_marginal_as_the_core_engine_does():
    bn = chain_net(8, 2, 3, extra_parents=1)  # 256 states: both engines
    qs = {"X2": [0.3, 0.7], "X5": [0.8, 0.2], "X7": [0.45, 0.55]}
    jt = make_engine(bn, method="junction").query(list(bn.nodes), {"X0": 1}, qs, "jeffrey")
    core = make_engine(bn, method="core").query(list(bn.nodes), {"X0": 1}, qs, "jeffrey")
    for n, q in qs.items():
        np.testing.assert_allclose(jt[n], q, atol=1e-10)
    for n in bn.nodes:
        np.testing.assert_allclose(jt[n], core[n], atol=1e-10)


def test_jeffrey_on_an_excluded_value_is_impossible():
    bn = chain_net(4, 2, 4)
    bn.cpts["X1"][...] = [1.0, 0.0]  # X1 is always v0
    eng = make_engine(bn, method="junction")
    with pytest.raises(ImpossibleEvidenceError, match=r"impossible evidence: soft\(X1\)"):
        eng.query(["X0"], soft={"X1": [0.5, 0.5]}, soft_rule="jeffrey")
    np.testing.assert_allclose(eng.query(["X1"], soft={"X1": [1.0, 0.0]}, soft_rule="jeffrey")["X1"], [1, 0])


def test_a_tiny_likelihood_on_the_only_possible_value_is_not_called_impossible():
    bn = chain_net(5, 3, 5)
    bn.cpts["X1"][...] = 0.0
    bn.cpts["X1"][..., 2] = 1.0  # X1 = v2 always
    eng = make_engine(bn, method="junction")
    for tiny in (1e-300, 1e-320):
        got = eng.query(["X3"], soft={"X1": [0.5, 0.5 - tiny, tiny]})["X3"]
        np.testing.assert_allclose(got, brute_force(bn, "X3", {}), atol=1e-12)
    with pytest.raises(ImpossibleEvidenceError, match="the hard evidence alone is possible"):
        eng.query(["X3"], soft={"X1": [0.5, 0.5, 0.0]})


def test_many_observations_of_small_probability_do_not_underflow():
    """600 observed nodes, P(evidence) far below 1e-250: the posterior is still exact (a renormalised run)."""
    bn = chain_net(601, 2, 6)
    rng = np.random.default_rng(0)
    hard = {f"X{i}": int(rng.integers(2)) for i in range(1, 601)}
    # closed form in logs: X0's posterior ∝ P(X0) Π_{children c of X0} P(x_c | X0); the rest is constant
    children = [x for x, ps in bn.parents.items() if ps == ("X0",)]
    log_post = np.log(bn.cpts["X0"]) + sum(np.log(bn.cpts[c][:, hard[c]]) for c in children)
    others = sum(
        np.log(bn.cpts[x][tuple(hard[p] for p in bn.parents[x]) + (hard[x],)])
        for x in bn.nodes
        if x != "X0" and x not in children
    )
    log_pe = others + np.logaddexp(*log_post)
    assert log_pe < np.log(1e-250)  # the evidence is that improbable
    got = make_engine(bn, method="junction").query(["X0"], hard)["X0"]
    np.testing.assert_allclose(got, np.exp(log_post - np.logaddexp(*log_post)), rtol=1e-9)


def test_probability_of_evidence_equals_pyagrum(tmp_path):
    from glu.bn.exchange import to_xmlbif

    bn = chain_net(20, 3, 7, extra_parents=2)
    path = tmp_path / "net.bifxml"
    path.write_text(to_xmlbif(bn))
    ie = gum.LazyPropagation(gum.loadBN(str(path)))
    eng = make_engine(bn, method="junction")
    rng = np.random.default_rng(1)
    for _ in range(20):
        hard = {f"X{i}": int(rng.integers(3)) for i in rng.choice(20, size=4, replace=False)}
        ie.eraseAllEvidence()
        ie.setEvidence(hard)
        ie.makeInference()
        assert eng.probability_of_evidence(hard) == pytest.approx(ie.evidenceProbability(), rel=1e-10)
    assert eng.probability_of_evidence({}) == pytest.approx(1.0)


# ---------------------------------------------------------------- batches
@pytest.mark.parametrize("deduplicate", [True, False])
def test_a_batch_equals_single_queries(deduplicate):
    """Two patterns of observed nodes, soft evidence in every row; identical rows answered once or not."""
    bn = chain_net(18, 3, 8, extra_parents=2)
    eng = make_engine(bn, method="junction")
    eng.deduplicate = deduplicate
    rng = np.random.default_rng(2)
    n = 120
    cols = {x: rng.integers(0, 3, n) for x in ("X3", "X9", "X15")}
    cols["X9"][rng.random(n) < 0.3] = -1  # two patterns
    soft = {"X12": rng.dirichlet(np.ones(3), size=n)}
    targets = ["X0", "X9", "X12", "X17"]
    for rule in ("virtual", "jeffrey"):
        out = eng.query_batch(targets, cols, soft=soft, soft_rule=rule, errors="nan")
        for i in range(0, n, 7):
            ev = {x: int(c[i]) for x, c in cols.items() if c[i] >= 0}
            try:
                single = eng.query(targets, ev, soft={"X12": soft["X12"][i]}, soft_rule=rule)
            except ImpossibleEvidenceError:
                assert np.isnan(out["X0"][i]).all()
                continue
            for t in targets:
                np.testing.assert_allclose(out[t][i], single[t], atol=1e-12)


def test_a_batch_names_its_first_impossible_row():
    bn = chain_net(6, 2, 9)
    bn.cpts["X2"][...] = 0.0
    bn.cpts["X2"][..., 0] = 1.0  # X2 = v0 always
    eng = make_engine(bn, method="junction")
    cols = {"X2": np.array([0] * 40 + [1] + [0] * 9), "X4": np.zeros(50, dtype=int)}
    with pytest.raises(ImpossibleEvidenceError, match=r"^row 40: impossible evidence: X2=v1, X4=v0"):
        eng.query_batch(["X0"], cols)
    out = eng.query_batch(["X0", "X2"], cols, errors="nan")
    assert np.isnan(out["X0"][40]).all() and np.isfinite(out["X0"][:40]).all()
    np.testing.assert_allclose(out["X2"][0], [1.0, 0.0])


def test_glus_network_on_the_junction_tree_equals_the_core_engine(zero_bn):
    """GLU's network (all-zero word rows included): the junction tree gives the core engine's answers."""
    core, jt = make_engine(zero_bn), make_engine(zero_bn, method="junction")
    assert core.method == "core"
    rng = np.random.default_rng(3)
    nodes = list(zero_bn.nodes)
    checked = 0
    for _ in range(30):
        hard = {str(n): int(rng.integers(zero_bn.schema.cardinality(str(n)))) for n in rng.choice(nodes, 3)}
        soft = {"Action": rng.dirichlet(np.ones(3))} if "Action" not in hard else None
        for rule in ("virtual", "jeffrey"):
            try:
                ref = core.query(nodes, hard, soft, rule)
            except ImpossibleEvidenceError:
                with pytest.raises(ImpossibleEvidenceError):
                    jt.query(nodes, hard, soft, rule)
                continue
            got = jt.query(nodes, hard, soft, rule)
            for n in nodes:
                np.testing.assert_allclose(got[n], ref[n], atol=1e-12)
            np.testing.assert_allclose(
                jt.word_probability_array(hard, soft, rule),
                core.word_probability_array(hard, soft, rule),
                atol=1e-12,
            )
            checked += 1
    assert checked > 20
    assert jt.probability_of_evidence({"Action": "tap"}) == pytest.approx(
        core.probability_of_evidence({"Action": "tap"}), rel=1e-12
    )


_COMPILE_ONCE = """
import sys, types
from glu.bn import kernels, make_engine, plan
from glu.jit import compiled
sys.path.insert(0, sys.argv[1])
from test_junction import chain_net

plan.TRY_ALL_ABOVE = 0  # every heuristic tried: triangulate with a code that varies
make_engine(chain_net(12, 3, seed=4, extra_parents=2), method="junction").posterior("X0", {"X11": "v1"})
for name, obj in vars(kernels).items():
    if isinstance(obj, types.FunctionType) and obj.__module__ == kernels.__name__:
        obj = compiled(obj)  # an entry point (helpers are bound to their compiled selves once compiled)
    if getattr(obj, "signatures", None):
        print(name, len(obj.signatures))
"""


@pytest.mark.slow
def test_each_planning_loop_is_compiled_once(tmp_path):
    """Compiled from an empty cache, after planning by every heuristic, each loop of glu.bn.kernels has one
    machine-code version: a literal argument (``triangulate(…, 0)``) had numba compile a loop and all it calls
    once more, which made a fresh machine's first junction-tree query take 21 s instead of 12
    (benchmarks/bench_kernels.py). Slow: it compiles every loop (about 12 s)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    out = subprocess.run(
        [sys.executable, "-c", _COMPILE_ONCE, str(Path(__file__).parent)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    versions = dict(line.split() for line in out.splitlines())
    assert {"plan_pattern", "triangulate", "eliminate", "_key", "_gains", "_bit", "_tree", "schedule"} <= set(
        versions
    )
    assert {name: n for name, n in versions.items() if n != "1"} == {}


def test_engines_pickle_for_dask_workers(zero_bn):
    """The sweep ships engines to Dask workers: both engines survive pickling and answer the same."""
    import pickle

    for eng in (make_engine(zero_bn), make_engine(chain_net(20, 3, 13, extra_parents=2))):
        node = eng.nodes[-1]
        eng.query([node], {eng.nodes[0]: 0})
        back = pickle.loads(pickle.dumps(eng))
        assert type(back) is type(eng)
        np.testing.assert_array_equal(
            back.query([node], {eng.nodes[0]: 0})[node], eng.query([node], {eng.nodes[0]: 0})[node]
        )


# ---------------------------------------------------------------- the size limit
def test_the_size_limit_refuses_in_one_line_with_the_estimate_and_the_width(monkeypatch):
    bn = chain_net(14, 2, 10)
    bn.parents["X13"]  # noqa: B018 - the network below gives X13 twelve parents: a 2**13 table
    names = bn.nodes
    parents = {**bn.parents, "X13": tuple(names[:12])}
    cpts = {**bn.cpts, "X13": np.full((2,) * 13, 0.5)}
    big = BayesNet(schema=bn.schema, parents=parents, cpts=cpts)
    with pytest.raises(ModelError) as e:  # refused when a query needs the table, before it is built
        make_engine(big, method="junction", max_table=1000).query(["X13"])
    msg = str(e.value)
    assert "\n" not in msg and "8,192 entries" in msg and "elimination width 12" in msg and "1,000" in msg
    small = make_engine(big, method="junction", max_table=1000)
    assert small.query(["X1"], {"X0": 0})["X1"].shape == (2,)  # a query that needs no large table
    monkeypatch.setenv(MAX_TABLE_ENV, "4096")
    with pytest.raises(ModelError, match=re.escape("the limit is 4,096")):
        make_engine(big, method="junction").junction_tree()
    monkeypatch.setenv(MAX_TABLE_ENV, "8192")
    assert make_engine(big, method="junction").junction_tree().largest == 8192
    monkeypatch.setenv(MAX_TABLE_ENV, "lots")
    with pytest.raises(ModelError, match=r"\$GLU_MAX_TABLE='lots': expected a whole number"):
        max_table_setting()


def test_the_estimate_is_made_before_any_table_is_built():
    """A network needing ~10**18 entries is refused at once (no table is ever allocated)."""
    n = 70
    names = [f"Y{i}" for i in range(n)]
    parents = {x: (tuple(names[max(0, i - 20) : i])) for i, x in enumerate(names)}
    plan_cards = [3] * n
    with pytest.raises(ModelError, match="elimination width"):
        plan_junction_tree(names, parents, plan_cards, max_table=1 << 24)


def test_the_cli_refuses_a_network_past_the_limit_in_one_line(tmp_path, capsys, monkeypatch):
    from glu.cli import main

    bn = chain_net(20, 2, 11)  # 2**20 core states: the junction tree
    parents = {**bn.parents, "X19": tuple(bn.nodes[:12])}
    big = BayesNet(schema=bn.schema, parents=parents, cpts={**bn.cpts, "X19": np.full((2,) * 13, 0.5)})
    model = tmp_path / "big.json"
    big.save(model)
    monkeypatch.setenv(MAX_TABLE_ENV, "1000")
    assert main(["query", "--model", str(model), "--target", "X19"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "elimination width 12" in err
    assert main(["query", "--model", str(model), "--target", "X19", "--max-table", "9000", "--json"]) == 0


def test_unknown_node_and_bad_soft_evidence_are_clear(tmp_path):
    eng = make_engine(chain_net(12, 3, 12, extra_parents=2), method="junction")
    with pytest.raises(EvidenceError, match="given twice"):
        eng.query(["X0"], {"X3": 1}, soft={"X3": [0.2, 0.3, 0.5]})
    with pytest.raises(EvidenceError, match="not a distribution"):
        eng.query(["X0"], soft={"X3": [0.2, 0.3, 0.6]})
    with pytest.raises(ValueError, match="unknown node 'X99'"):
        eng.query(["X99"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        eng.query_batch(["X0"], {"X3": [0, 1, None, float("nan")]})


def test_limits_that_are_not_whole_numbers_and_cores_too_large_are_refused(monkeypatch):
    for bad in (0, -5, 2.5, True, "1000"):
        with pytest.raises(
            ModelError, match=rf"^max_table={bad!r}: expected a whole number of table entries ≥ 1$"
        ):
            max_table_setting(bad)
    monkeypatch.setenv(MAX_TABLE_ENV, "0")
    with pytest.raises(ModelError, match=r"^\$GLU_MAX_TABLE=0: expected a whole number"):
        max_table_setting()
    big = chain_net(23, 2, 0)  # 2**23 core states: past the core engine's 2**22
    with pytest.raises(ModelError, match="has 8,388,608 states; the core engine handles up to 4,194,304"):
        make_engine(big, method="core").query(["X0"])
    assert make_engine(big).method == "junction"


def test_a_clique_wider_than_numpys_axes_is_refused_before_any_table():
    """62 nodes, each a child of all before it: one clique of all 62 (more axes than NumPy's 64 allow once
    the rows are added), refused whatever the table limit."""
    names = [f"Y{i}" for i in range(62)]
    parents = {x: tuple(names[:i]) for i, x in enumerate(names)}
    with pytest.raises(ModelError, match=r"a table over 62 variables \(elimination width 61\); NumPy arrays"):
        plan_junction_tree(names, parents, [2] * 62, max_table=1 << 62)


def test_rows_impossible_elsewhere_give_nan_on_a_target_their_evidence_does_not_reach():
    """X1 is always a0; Y1's row for Y0 = b is all zeros (a word never seen there), so P(Y0 = a) = 1 in
    every possible row, and the row observing X1 = a1 is impossible: NaN on both engines."""
    vals = {n: ("a", "b") for n in ("X0", "X1", "Y0")} | {"Y1": ("absent", "present")}
    parents = {"X0": (), "X1": ("X0",), "Y0": (), "Y1": ("Y0",)}
    cpts = {
        "X0": np.array([0.5, 0.5]),
        "X1": np.array([[1.0, 0.0], [1.0, 0.0]]),
        "Y0": np.array([0.4, 0.6]),
        "Y1": np.array([[0.9, 0.1], [0.0, 0.0]]),
    }
    bn = BayesNet(schema=Schema(values=vals, n_affordance=3), parents=parents, cpts=cpts)
    for method in ("junction", "core"):
        out = make_engine(bn, method=method).query_batch(["Y0"], {"X1": np.array([0, 1, 0])}, errors="nan")
        np.testing.assert_array_equal(out["Y0"], [[1.0, 0.0], [np.nan, np.nan], [1.0, 0.0]])
