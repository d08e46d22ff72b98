"""The papers' network experiments: the TCDS threshold against a grid, and every table's provenance."""

from __future__ import annotations

import numpy as np
import pytest

from glu.bn import make_engine
from glu.fusion import fuse
from glu.studies.replication import fusion as experiments


@pytest.mark.parametrize(
    "evidence", [{"Size": "small", "Shape": "sphere", "ObjVel": "slow"}, {"Shape": "box"}]
)
def test_tap_threshold_by_bisection_agrees_with_a_fine_grid(zero_bn, evidence):
    t = experiments.tap_threshold(zero_bn, evidence)
    eng = make_engine(zero_bn)
    ev = evidence

    def tap_wins(x):
        post = fuse(eng, ["Action"], ev, [(1 - x) / 2, x, (1 - x) / 2], "product")["Action"]
        return post[1] > max(post[0], post[2])

    grid = np.linspace(0, 1, 3001)  # the first crossing on the grid; t itself is pinned to 1e-9 below
    wins = [tap_wins(x) for x in grid]
    if np.isnan(t):
        assert not any(wins)
        return
    first = grid[np.argmax(wins)]
    assert abs(first - t) <= (grid[1] - grid[0])
    assert not tap_wins(t - 1e-9) and tap_wins(t + 1e-9)


def test_tables_are_stamped_with_their_provenance(zero_bn, uniform_bn):
    for df in (
        experiments.effect_prediction(zero_bn),
        experiments.tap_thresholds(zero_bn),
        experiments.unseen_rows_comparison(zero_bn, uniform_bn),
    ):
        assert df.attrs["experiment"] and df.attrs["data_source"] == zero_bn.meta["data_source"]
        assert isinstance(df.attrs["parameters"], dict)
    sweep = experiments.soft_evidence_sweep(zero_bn, {"Shape": "sphere"}, n_points=5, rules=("jeffrey",))
    assert sweep.attrs["parameters"] == {"evidence": {"Shape": "sphere"}, "n_points": 5, "rules": ["jeffrey"]}


def _without(bn, value, actions):
    """``bn`` with P(ObjVel=value | Action=a, …) = 0 for the ``actions`` (their rows renormalised)."""
    from dataclasses import replace

    cpt = bn.cpts["ObjVel"].copy()
    v = bn.schema.values_of("ObjVel").index(value)
    for a in actions:
        i = bn.schema.values_of("Action").index(a)
        cpt[i, ..., v] = 0.0
        cpt[i] /= cpt[i].sum(axis=-1, keepdims=True)
    return replace(bn, cpts={**bn.cpts, "ObjVel": cpt})


def test_evidence_tap_cannot_have_or_nothing_can(zero_bn):
    """Objects that taps never leave still: tap never wins on a still object, whatever the HMMs say (nan);
    objects that no action leaves still: no row of the thresholds' table for them."""
    no_slow_tap = _without(zero_bn, "slow", ["tap"])
    eng = make_engine(no_slow_tap)
    assert eng.query(["Action"], {"ObjVel": "slow"})["Action"][1] == 0
    assert np.isnan(experiments.tap_threshold(no_slow_tap, {"ObjVel": "slow"}))
    table = experiments.tap_thresholds(_without(zero_bn, "slow", ["grasp", "tap", "touch"]))
    assert "slow" not in set(table.ObjVel) and len(table) == 2 * 3 * 2  # Shape × Size × {medium, fast}
