"""Model files: JSON round trip, the original .mat import, and clear errors for malformed models."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
import scipy.io as sio

from glu.bn import BayesNet
from glu.errors import ModelError


def test_json_round_trip_is_bit_exact(zero_bn, tmp_path):
    original_bn = zero_bn
    p = original_bn.save(tmp_path / "orig.json")
    back = BayesNet.load(p)
    assert back.edges() == original_bn.edges()
    assert back.schema.nodes == original_bn.schema.nodes
    for n in original_bn.nodes:
        np.testing.assert_array_equal(back.cpts[n], original_bn.cpts[n])
    doc = json.loads(p.read_text())
    assert doc["format"] == "glu-bayesnet" and doc["version"] == 1 and doc["n_affordance"] == 8
    objvel = next(d for d in doc["nodes"] if d["name"] == "ObjVel")
    assert objvel["parents"] == ["Action", "Shape", "Size"]
    assert np.asarray(objvel["cpt"]).shape == (3, 2, 3, 3)


def write_bnt_mat(bn: BayesNet, path, variable: str = "netobj_lab", do_compression: bool = False) -> None:
    """Write ``bn`` as the originals' MATLAB code saved it (BNT struct), independently of glu's reader.

    ``dag[i, j] = 1`` for an edge i → j; ``CPD{k}.CPT[i_1, …, i_m, v]`` with parents in node order; the
    Shape value ``sphere`` is written as the files' ``circle``; word nodes have no value names.
    """
    names = list(bn.nodes)
    dag = np.zeros((len(names), len(names)))
    for parent, child in bn.edges():
        dag[names.index(parent), names.index(child)] = 1
    value_names = np.empty(bn.schema.n_affordance, dtype=object)
    for i, n in enumerate(names[: bn.schema.n_affordance]):
        value_names[i] = np.array(
            [{"sphere": "circle"}.get(v, v) for v in bn.schema.values_of(n)], dtype=object
        )
    cpds = np.empty(len(names), dtype=object)
    for k, n in enumerate(names):
        cpds[k] = {"CPT": bn.cpts[n]}
    net = {
        "nodeNames": np.array(names, dtype=object),
        "nodeValueNames": value_names,
        "AFFORDNODES": np.arange(1, bn.schema.n_affordance + 1, dtype=float),
        "dag": dag,
        "bnet": {"CPD": cpds},
    }
    sio.savemat(path, {variable: net}, do_compression=do_compression)


def test_mat_import_reads_the_bnt_layout(zero_bn, tmp_path):
    path = tmp_path / "BN.mat"
    write_bnt_mat(zero_bn, path)
    back = BayesNet.from_bnt_mat(path)
    assert back.nodes == zero_bn.nodes and back.edges() == zero_bn.edges()
    assert back.schema.values_of("Shape") == ("sphere", "box")
    assert back.schema.values_of("rolls") == ("absent", "present")
    for n in zero_bn.nodes:
        np.testing.assert_array_equal(back.cpts[n], zero_bn.cpts[n])
    assert back.zero_rows() == zero_bn.zero_rows()


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("not json", "not a JSON model file"),
        ('{"format": "other"}', "not a glu Bayesian network"),
        ('{"format": "glu-bayesnet", "version": 9}', "unsupported version 9"),
        (
            '{"format": "glu-bayesnet", "version": 1, "n_affordance": 1, "nodes": [{"name": "A"}]}',
            "malformed model",
        ),
    ],
)
def test_malformed_json_models(tmp_path, content, message):
    p = tmp_path / "m.json"
    p.write_text(content)
    with pytest.raises(ModelError, match=message):
        BayesNet.load(p)


def _doc(cpt_b, parents_b=("A",), parents_a=()):
    return {
        "format": "glu-bayesnet",
        "version": 1,
        "n_affordance": 2,
        "nodes": [
            {
                "name": "A",
                "values": ["a0", "a1"],
                "parents": list(parents_a),
                "cpt": [0.5, 0.5] if not parents_a else [[0.5, 0.5]] * 2,
            },
            {"name": "B", "values": ["b0", "b1"], "parents": list(parents_b), "cpt": cpt_b},
        ],
    }


def _chain(n: int, closed: bool) -> dict:
    """A chain X0 -> X1 -> … of ``n`` binary nodes; ``closed``: X0 also has the last node as its parent."""
    nodes = []
    for i in range(n):
        parents = [f"X{i - 1}"] if i else ([f"X{n - 1}"] if closed else [])
        cpt = [[0.5, 0.5]] * 2 if parents else [0.5, 0.5]
        nodes.append({"name": f"X{i}", "values": ["a", "b"], "parents": parents, "cpt": cpt})
    return {"format": "glu-bayesnet", "version": 1, "n_affordance": n, "nodes": nodes}


def test_a_chain_deeper_than_pythons_recursion_limit_is_checked_for_cycles():
    """The acyclicity check walks no recursion: a chain of 3,000 nodes is valid, and closed into a loop it
    is refused with the loop named in one line (the recursive search before it said "malformed model
    (RecursionError: maximum recursion depth exceeded …)" for this loop)."""
    assert len(BayesNet.from_dict(_chain(3000, closed=False)).nodes) == 3000
    with pytest.raises(ModelError) as e:
        BayesNet.from_dict(_chain(3000, closed=True))
    message = str(e.value)
    assert "\n" not in message and len(message) < 200, message  # one readable line, not 3,000 names
    names = re.fullmatch(r"model: the graph has a cycle: (.*)", message).group(1).split(" -> ")
    first, last = int(names[0][1:]), int(names[-1][1:])
    assert names[0] == names[-1] and names[5] == "… (2,992 more) …", names
    for a, b in zip(names[:4], names[1:5], strict=True):  # each name a parent of the next, along the chain
        assert int(b[1:]) == (int(a[1:]) + 1) % 3000
    for a, b in zip(names[6:-1], names[7:], strict=True):
        assert int(b[1:]) == (int(a[1:]) + 1) % 3000
    assert (int(names[6][1:]) - int(names[4][1:])) % 3000 == 2993 and first == last


def test_model_validation_errors(tmp_path):
    with pytest.raises(ModelError, match="CPT shape"):
        BayesNet.from_dict(_doc([0.5, 0.5]))
    with pytest.raises(ModelError, match="must sum to 1"):
        BayesNet.from_dict(_doc([[0.5, 0.6], [0.5, 0.5]]))
    with pytest.raises(ModelError, match="non-negative"):
        BayesNet.from_dict(_doc([[1.5, -0.5], [0.5, 0.5]]))
    with pytest.raises(ModelError, match="cycle"):
        BayesNet.from_dict(_doc([[0.5, 0.5], [0.5, 0.5]], parents_a=("B",)))
    with pytest.raises(ModelError, match="all-zero rows are for word nodes only"):
        BayesNet.from_dict(_doc([[0.0, 0.0], [0.5, 0.5]]))  # B is an affordance node here
    ok = BayesNet.from_dict({**_doc([[0.0, 0.0], [0.5, 0.5]]), "n_affordance": 1})  # a word may have one
    assert ok.zero_rows() == {"B": 1}
    with pytest.raises(ModelError, match="distinct"):
        doc = _doc([[0.5, 0.5], [0.5, 0.5]])
        doc["nodes"][1]["values"] = ["b0", "b0"]
        BayesNet.from_dict(doc)
    with pytest.raises(ModelError, match="no such model file"):
        BayesNet.load(tmp_path / "missing.json")
    with pytest.raises(ModelError, match="no such file"):
        BayesNet.from_bnt_mat(tmp_path / "missing.mat")
