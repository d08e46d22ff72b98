"""Fusion strategies against closed forms built from pgmpy's hard-evidence posteriors (synthetic and real
data)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from glu.bn import make_engine
from glu.errors import EvidenceError
from glu.fusion import fuse, hmm_rows

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from bn_reference import to_pgmpy_with_zero_rows
    from pgmpy.inference import VariableElimination

ACTIONS = ("grasp", "tap", "touch")


@pytest.fixture(scope="module")
def ref(zero_bn):
    model, seen = to_pgmpy_with_zero_rows(zero_bn)
    ve = VariableElimination(model)

    def p(target, evidence):
        return ve.query([target], evidence={**evidence, **seen}, show_progress=False).values

    return p


@pytest.fixture(scope="module")
def engine(zero_bn):
    return make_engine(zero_bn)


CASES = [
    ({"Shape": "sphere"}, "ObjVel"),
    ({"Size": "small", "Shape": "sphere"}, "rolls"),
    ({"Shape": "box"}, "Contact"),
]
Q = np.array([0.2, 0.5, 0.3])


@pytest.mark.parametrize(("evidence", "target"), CASES)
def test_hard_decision_uses_the_top_action(engine, ref, evidence, target):
    got = fuse(engine, [target], evidence, Q, "hard")[target]
    np.testing.assert_allclose(got, ref(target, {**evidence, "Action": "tap"}), atol=1e-9)


@pytest.mark.parametrize(("evidence", "target"), CASES)
def test_virtual_evidence_closed_form(engine, ref, evidence, target):
    """Σ_A p(X, A | e) q(A) / Σ_A p(A | e) q(A), each term from pgmpy."""
    p_a = ref("Action", evidence)
    num = sum(p_a[i] * Q[i] * ref(target, {**evidence, "Action": a}) for i, a in enumerate(ACTIONS))
    expected = num / float(np.dot(p_a, Q))
    np.testing.assert_allclose(fuse(engine, [target], evidence, Q, "virtual")[target], expected, atol=1e-9)


@pytest.mark.parametrize(("evidence", "target"), CASES)
def test_jeffrey_rule_closed_form(engine, ref, evidence, target):
    expected = sum(Q[i] * ref(target, {**evidence, "Action": a}) for i, a in enumerate(ACTIONS))
    np.testing.assert_allclose(fuse(engine, [target], evidence, Q, "jeffrey")[target], expected, atol=1e-9)


def test_product_rule_and_tcds_action_case(engine, ref):
    evidence = {"Size": "small", "Shape": "sphere", "ObjVel": "slow"}
    p_bn = ref("Action", evidence)
    expected = p_bn * Q / np.dot(p_bn, Q)
    np.testing.assert_allclose(
        fuse(engine, ["Action"], evidence, Q, "product")["Action"], expected, atol=1e-9
    )
    # TCDS: with Action among the inferred variables, the soft decision is the product rule
    np.testing.assert_allclose(
        fuse(engine, ["Action"], evidence, Q, "virtual")["Action"], expected, atol=1e-9
    )
    with pytest.raises(EvidenceError, match="targets must be"):
        fuse(engine, ["ObjVel"], evidence, Q, "product")


def test_observing_action_with_gesture_evidence_is_refused(engine):
    with pytest.raises(EvidenceError, match="Action is observed directly"):
        fuse(engine, ["ObjVel"], {"Action": "tap"}, Q, "virtual")
    with pytest.raises(EvidenceError, match="unknown fusion strategy"):
        fuse(engine, ["ObjVel"], {}, Q, "average")
    with pytest.raises(EvidenceError, match="not a distribution"):
        fuse(engine, ["ObjVel"], {}, [0.5, 0.5, 0.5], "virtual")


def test_no_gesture_evidence_is_the_bn_alone(engine, ref):
    np.testing.assert_allclose(
        fuse(engine, ["ObjVel"], {"Shape": "box"}, None)["ObjVel"], ref("ObjVel", {"Shape": "box"}), atol=1e-9
    )


def test_hmm_rows():
    rows = hmm_rows([1 / 3, 0.8, 1.0])
    np.testing.assert_allclose(rows, [[1 / 3] * 3, [0.1, 0.8, 0.1], [0, 1, 0]])
