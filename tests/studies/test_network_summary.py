"""The learned network in numbers (notebook 03's bn_learning_summary) against brute force and the original."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from glu.bn.model import encode
from glu.studies.replication.fusion import network_summary


def brute_force_mass(bn) -> float:
    """Σ over every affordance configuration of Π affordance CPTs × Π_words Σ_v CPT_w (a zero row gives 0)."""
    aff = bn.schema.nodes[: bn.schema.n_affordance]
    total = 0.0
    for combo in itertools.product(*(range(bn.schema.cardinality(n)) for n in aff)):
        val = dict(zip(aff, combo, strict=True))
        p = 1.0
        for n in bn.nodes:
            idx = tuple(val[q] for q in bn.parents[n])
            p *= bn.cpts[n][idx][val[n]] if n in val else bn.cpts[n][idx].sum()
        total += p
    return total


def test_network_summary_against_brute_force(zero_bn, table, source):
    df = network_summary(zero_bn, table).set_index("quantity")["ours"]
    assert df["edges"] == len(zero_bn.edges())
    assert df["zero_rows"] == sum(int((c.sum(axis=-1) == 0).sum()) for c in zero_bn.cpts.values())
    codes = encode(table, zero_bn.schema)
    by_rows = sum(
        np.log(zero_bn.cpts[n][tuple(codes[q][i] for q in zero_bn.parents[n]) + (codes[n][i],)])
        for i in range(0, len(table), 97)
        for n in zero_bn.nodes
    )
    sub = network_summary(zero_bn, table.iloc[::97].reset_index(drop=True)).set_index("quantity")["ours"]
    assert sub["log_likelihood"] == pytest.approx(by_rows, rel=1e-12)
    assert df["lost_prior_mass"] == pytest.approx(1 - brute_force_mass(zero_bn), abs=1e-12)
