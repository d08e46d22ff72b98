"""Model files: JSON round trip, the original .mat import, and clear errors for malformed models."""

from __future__ import annotations

import json
import re
import struct

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


def test_children_are_the_nodes_naming_the_node_as_parent():
    """A chain X0 -> X1 -> X2, and B with parent A: each node's children, by hand."""
    chain = BayesNet.from_dict(_chain(3, closed=False))
    assert [chain.children(x) for x in ("X0", "X1", "X2")] == [("X1",), ("X2",), ()]
    two = BayesNet.from_dict(_doc([[0.9, 0.1], [0.2, 0.8]]))
    assert (two.children("A"), two.children("B")) == (("B",), ())


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


def _edited(edit) -> dict:
    doc = _doc([[0.5, 0.5], [0.25, 0.75]])
    edit(doc)
    return doc


TWO_PARENTS = [[[0.5, 0.5]] * 2] * 2


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.update(nodes=[], n_affordance=0), "a model needs at least one node"),
        (lambda d: d["nodes"][1].update(name="A"), "a node name appears twice"),
        (lambda d: d.update(schema=["roles"]), '"schema" must be an object, not list'),
        (lambda d: d.update(schema={"roles": {"A": "verb"}}), r"unknown role\(s\) \['verb'\]; roles are"),
        (lambda d: d["nodes"][1].update(parents=["Z"]), "node 'B': unknown parent 'Z'"),
        (lambda d: d["nodes"][1].update(parents=["A", "A"], cpt=TWO_PARENTS), "node 'B': parents must be"),
        (
            lambda d: d["nodes"].append(
                {**d["nodes"][1], "name": "C", "parents": ["B", "A"], "cpt": TWO_PARENTS}
            ),
            r"node 'C': parents must be distinct and in node order, got \['B', 'A'\]",
        ),
    ],
    ids=["no-nodes", "name-twice", "schema-not-object", "unknown-role", "unknown-parent", "twice", "order"],
)
def test_malformed_model_documents_are_one_line(edit, message):
    with pytest.raises(ModelError, match="^m.json: " + message) as e:
        BayesNet.from_dict(_edited(edit), "m.json")
    assert "\n" not in str(e.value)


def test_a_model_needs_parents_and_cpts_for_exactly_its_nodes():
    bn = BayesNet.from_dict(_doc([[0.5, 0.5], [0.25, 0.75]]))
    with pytest.raises(ModelError, match="parents and CPTs must be given for exactly the schema's nodes"):
        BayesNet(schema=bn.schema, parents={"A": ()}, cpts=bn.cpts)


def test_a_table_of_value_names_is_encoded_and_scored():
    """Plain strings (not categoricals): log P = log P(a1) + log P(b1 | a1) + log P(a0) + log P(b0 | a0)."""
    import pandas as pd

    from glu.errors import DataError

    bn = BayesNet.from_dict({**_doc([[0.5, 0.5], [0.25, 0.75]]), "n_affordance": 2})
    bn.cpts["A"][:] = [0.4, 0.6]
    df = pd.DataFrame({"A": ["a1", "a0"], "B": ["b1", "b0"]})
    assert bn.log_likelihood(df) == pytest.approx(np.log(0.6 * 0.75 * 0.4 * 0.5), rel=1e-12)
    with pytest.raises(DataError, match="the table has no column 'B'"):
        bn.log_likelihood(df[["A"]])
    with pytest.raises(DataError, match=r"column 'B': missing or unknown values; allowed: \('b0', 'b1'\)"):
        bn.log_likelihood(df.assign(B=["b1", "b2"]))


def _bnt_file(path, **changes) -> None:
    """A BNT network A → w (a word) as the originals saved it, with ``changes`` to its fields."""
    cpds = np.empty(2, dtype=object)
    cpds[0], cpds[1] = {"CPT": np.array([0.5, 0.5])}, {"CPT": np.array([[0.2, 0.8], [0.6, 0.4]])}
    value_names = np.empty(1, dtype=object)
    value_names[0] = np.array(["a0", "a1"], dtype=object)
    net = {
        "nodeNames": np.array(["A", "w"], dtype=object),
        "nodeValueNames": value_names,
        "AFFORDNODES": np.array([1.0]),
        "dag": np.array([[0.0, 1.0], [0.0, 0.0]]),
        "bnet": {"CPD": cpds},
    }
    sio.savemat(path, {"netobj_lab": {**net, **changes}})


def test_a_bnt_network_with_one_affordance_node_reads(tmp_path):
    """Its value names are a 1 × 1 cell, which SciPy squeezes to the names themselves (glu read A's
    first value name as a node's only value, then refused the file: "cannot reshape array of size 2")."""
    path = tmp_path / "BN.mat"
    _bnt_file(path)
    bn = BayesNet.from_bnt_mat(path)
    assert bn.schema.values == {"A": ("a0", "a1"), "w": ("absent", "present")} and bn.parents["w"] == ("A",)
    np.testing.assert_array_equal(bn.cpts["w"], [[0.2, 0.8], [0.6, 0.4]])


def test_inconsistent_bnt_networks_are_one_line(tmp_path):
    path = tmp_path / "BN.mat"
    _bnt_file(path, dag=np.zeros((3, 3)))
    with pytest.raises(
        ModelError, match=r"BN.mat: an inconsistent BNT network in 'netobj_lab': 2 node names "
    ):
        BayesNet.from_bnt_mat(path)
    _bnt_file(path, AFFORDNODES=np.zeros(0))
    with pytest.raises(ModelError, match="BN.mat: 0 affordance nodes among 2 nodes in 'netobj_lab'"):
        BayesNet.from_bnt_mat(path)


def test_a_mat_file_scipy_cannot_parse_is_one_line(tmp_path):
    """A character array of 5 declared characters holding 2: the structure is sound, SciPy's reading fails."""
    name = b"netobj_lab"
    head = b"MATLAB 5.0 MAT-file".ljust(116, b" ") + bytes(8) + b"\x00\x01IM"

    def el(t: int, payload: bytes) -> bytes:
        return struct.pack("<II", t, len(payload)) + payload + bytes(-len(payload) % 8)

    body = el(6, struct.pack("<II", 4, 0)) + el(5, struct.pack("<2i", 1, 5)) + el(1, name) + el(1, b"ab")
    path = tmp_path / "BN.mat"
    path.write_bytes(head + el(14, body))
    with pytest.raises(ModelError, match=r"BN.mat: not a readable MATLAB file \(TypeError: ") as e:
        BayesNet.from_bnt_mat(path)
    assert "\n" not in str(e.value)
