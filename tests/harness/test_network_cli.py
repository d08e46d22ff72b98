"""Networks from other tools on the command line and in the labelled API: import (rows that do not sum to 1),
``glu bn nodes``, ``glu query`` for every node (equal to pyAgrum), ``--target words``, pandas results."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from glu.bn import BayesNet, make_engine
from glu.bn.exchange import from_bif, import_bn, to_xmlbif
from glu.cli import main
from glu.errors import ModelError
from glu.paths import shared_data_dir

gum = pytest.importorskip("pyagrum")
SHARED = shared_data_dir()
NETWORKS = SHARED / "bn-networks" if SHARED is not None else None
needs_networks = pytest.mark.skipif(
    NETWORKS is None or not NETWORKS.is_dir(), reason="no bn-networks folder in $GLU_SHARED_DATA"
)

ROUNDED = """network r {{ }}
variable A {{ type discrete [ 2 ] {{ a0, a1 }}; }}
variable B {{ type discrete [ 3 ] {{ b0, b1, b2 }}; }}
probability ( A ) {{ table 0.3, 0.7; }}
probability ( B | A ) {{ (a0) 0.2, 0.3, 0.5; (a1) 0.2, 0.3, {last}; }}
"""


# ---------------------------------------------------------------- import: rows that do not sum to 1
def test_a_row_off_by_more_than_the_tolerance_is_named_with_its_parents(tmp_path, capsys):
    path = tmp_path / "r.bif"
    path.write_text(ROUNDED.format(last="0.50004"))  # sums to 1.00004
    with pytest.raises(ModelError) as e:
        import_bn(path)
    msg = str(e.value)
    assert "the row P(B | A=a1) sums to 1.00004, not 1" in msg and "--renormalise 0.0001" in msg
    assert main(["bn", "import", str(path), "-o", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "P(B | A=a1)" in err
    assert main(["bn", "import", str(path), "-o", str(tmp_path / "r.json"), "--renormalise", "1e-4"]) == 0
    out = capsys.readouterr().out
    assert (
        "rescaled 1 CPT row(s) to sum to 1 (largest |1 − sum| = 4e-05, in P(B | A=a1); tolerance 0.0001)"
        in out
    )
    model = BayesNet.load(tmp_path / "r.json")
    np.testing.assert_allclose(
        model.cpts["B"][1], np.array([0.2, 0.3, 0.50004]) / 1.00004, rtol=0, atol=1e-15
    )
    assert model.meta["renormalised"]["rows"] == 1
    with pytest.raises(SystemExit) as e:
        main(["bn", "import", str(path), "-o", str(tmp_path / "r.json"), "--renormalise", "2"])
    assert e.value.code == 2 and "a tolerance is a number in [0, 1)" in capsys.readouterr().err


def test_query_takes_the_renormalise_its_message_advises(tmp_path, capsys):
    path = tmp_path / "r.bif"
    path.write_text(ROUNDED.format(last="0.50004"))
    assert main(["query", "--model", str(path), "--target", "B"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "give --renormalise 0.0001" in err
    assert main(["query", "--model", str(path), "--renormalise", "1e-4", "--target", "B"]) == 0
    out = capsys.readouterr().out
    assert "1 CPT row(s) rescaled to sum to 1 on import" in out
    # P(B=b2) = 0.3 · 0.5 + 0.7 · 0.50004 / 1.00004, by hand
    assert f"{0.3 * 0.5 + 0.7 * 0.50004 / 1.00004:.6f}" in out


def test_rows_rounded_by_other_tools_are_rescaled_and_reported():
    bn = from_bif(ROUNDED.format(last="0.500001"), "r.bif")  # within the default 1e-5
    assert bn.meta["renormalised"] == {
        "rows": 1,
        "largest_deviation": pytest.approx(1e-6),
        "at": "P(B | A=a1)",
        "tolerance": 1e-5,
    }
    assert "renormalised" not in from_bif(ROUNDED.format(last="0.5"), "r.bif").meta
    with pytest.raises(ModelError, match=r"the row P\(B \| A=a1\) has an entry that is negative"):
        from_bif(ROUNDED.format(last="-0.5"), "r.bif")


@needs_networks
def test_insurance_imports_with_renormalise(tmp_path, capsys):
    src = NETWORKS / "insurance.bif"
    assert main(["bn", "import", str(src), "-o", str(tmp_path / "i.json")]) == 2
    err = capsys.readouterr().err
    assert "P(OtherCarCost | Accident=Mild, RuggedAuto=Football) sums to 1.000035" in err
    assert main(["bn", "import", str(src), "-o", str(tmp_path / "i.json"), "--renormalise"]) == 0
    assert "largest |1 − sum| = 3.5e-05, in P(OtherCarCost | Accident=Mild, RuggedAuto=Football)" in (
        capsys.readouterr().out
    )


# ---------------------------------------------------------------- glu query on imported networks
@needs_networks
@pytest.mark.parametrize("name", ["alarm", "child"])
def test_glu_query_answers_every_node_as_pyagrum(name, tmp_path, capsys):
    """`glu query --model NET.json --target …every node…` equals pyAgrum to 1e-9 (the issue's acceptance)."""
    model = tmp_path / f"{name}.json"
    assert main(["bn", "import", str(NETWORKS / f"{name}.bif"), "-o", str(model)]) == 0
    capsys.readouterr()
    bn = BayesNet.load(model)
    (tmp_path / "n.bifxml").write_text(to_xmlbif(bn))
    ie = gum.LazyPropagation(gum.loadBN(str(tmp_path / "n.bifxml")))
    nodes = list(bn.nodes)
    evidence = {nodes[3]: bn.schema.values_of(nodes[3])[0], nodes[-2]: bn.schema.values_of(nodes[-2])[-1]}
    for ev in ({}, evidence):
        args = ["query", "--model", str(model), "--target", *nodes, "--json"]
        if ev:
            args += ["--evidence", *(f"{k}={v}" for k, v in ev.items())]
        assert main(args) == 0
        answer = json.loads(capsys.readouterr().out)
        ie.eraseAllEvidence()
        ie.setEvidence(ev)
        ie.makeInference()
        for n in nodes:
            ref = ie.posterior(n).toarray()
            ours = np.array([answer[n][v] for v in bn.schema.values_of(n)])
            np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-9, err_msg=n)


def test_bn_nodes_lists_kinds_values_and_parents(zero_bn, tmp_path, capsys):
    model = tmp_path / "glu.json"
    zero_bn.save(model)
    assert main(["bn", "nodes", str(model)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].endswith("57 nodes, 49 of them word nodes")
    rows = {line.split()[0]: line for line in lines[2:]}
    assert rows["Action"].split()[1:5] == ["action", "grasp,", "tap,", "touch"]
    assert rows["ObjVel"].split()[1] == "effect" and rows["the"].split()[1] == "word"
    assert rows["Action"].rstrip().endswith("—")  # no parents


def test_query_target_words_gives_every_words_probability(zero_bn, tmp_path, capsys):
    model = tmp_path / "glu.json"
    zero_bn.save(model)
    eng = make_engine(zero_bn)
    assert (
        main(["query", "--model", str(model), "--target", "words", "--evidence", "Action=tap", "--json"]) == 0
    )
    words = json.loads(capsys.readouterr().out)["words"]
    assert list(words) == list(eng.binary_leaves)
    for w in ("rolls", "tapping", "the"):
        assert words[w] == pytest.approx(eng.query([w], {"Action": "tap"})[w][1], abs=1e-12)
    assert (
        main(["query", "--model", str(model), "--target", "words", "ObjVel", "--evidence", "Action=tap"]) == 0
    )
    out = capsys.readouterr().out
    assert "word      P(present)" in out and "ObjVel  slow" in out


# ---------------------------------------------------------------- labelled results
def test_the_api_gives_labelled_pandas_results(zero_bn):
    from glu.bn.exchange import from_xmlbif

    for eng in (make_engine(zero_bn), make_engine(zero_bn, method="junction")):
        m = eng.marginals({"Action": "tap"})
        assert set(m) == set(zero_bn.nodes)
        assert isinstance(m["ObjVel"], pd.Series) and list(m["ObjVel"].index) == ["slow", "medium", "fast"]
        np.testing.assert_allclose(m["ObjVel"], eng.query(["ObjVel"], {"Action": "tap"})["ObjVel"])
        w = eng.word_probabilities({"Action": "tap"})
        assert isinstance(w, pd.Series) and w.index.name == "word" and len(w) == 49
        np.testing.assert_allclose(w.to_numpy(), eng.word_probability_array({"Action": "tap"}))
        table = eng.posterior_table("ObjVel", pd.DataFrame({"Action": ["tap", "grasp"]}, index=["x", "y"]))
        assert list(table.index) == ["x", "y"] and list(table.columns) == ["slow", "medium", "fast"]
    net = from_xmlbif(to_xmlbif(zero_bn, zero_rows="seen"), "x")  # indicators folded back: same model
    assert make_engine(net).posterior("Action", {"rolls": "present"}).name == "Action"
