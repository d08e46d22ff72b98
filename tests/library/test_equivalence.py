"""The equivalence test (glu.stats.tost_p_value), against the closed-form normal TOST (Schuirmann 1987) and
brute force."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from glu.errors import DataError
from glu.stats import equivalence_verdict, percentile_interval, tost_p_value


def _normal_replicates(estimate: float, se: float, b: int) -> np.ndarray:
    """Row 0 the estimate, then ``b`` replicates at the normal quantiles (i − ½)/b: a bootstrap distribution
    that is exactly N(estimate, se²) up to its discreteness."""
    q = stats.norm.ppf((np.arange(1, b + 1) - 0.5) / b)
    return np.concatenate([[estimate], estimate + se * q])


@pytest.mark.parametrize(
    "estimate, se, margin", [(0.0, 0.01, 0.02), (-0.015, 0.01, 0.02), (0.03, 0.02, 0.05), (0.05, 0.01, 0.02)]
)
def test_tost_equals_the_normal_closed_form(estimate, se, margin):
    """For a normal estimate the TOST p-value is max(Φ((−m − d)/se), Φ((d − m)/se))."""
    b = 20000
    closed = max(stats.norm.cdf((-margin - estimate) / se), stats.norm.cdf((estimate - margin) / se))
    p = float(tost_p_value(_normal_replicates(estimate, se, b), margin))
    assert p == pytest.approx(closed, abs=2.0 / b)


def test_tost_by_counting():
    """Brute force: count, replicate by replicate, those at or beyond each margin."""
    rng = np.random.default_rng(4)
    reps = rng.normal(0.005, 0.012, size=(1001, 3))
    reps[:, 2] = np.nan
    reps[5:40, 1] = np.nan  # a column with some undefined replicates uses its finite ones
    m = 0.02
    p = tost_p_value(reps, m)
    for j in range(2):
        col = [x for x in reps[1:, j] if np.isfinite(x)]
        below = sum(1 for x in col if x <= -m)
        above = sum(1 for x in col if x >= m)
        assert p[j] == pytest.approx(max(1 + below, 1 + above) / (len(col) + 1))
    assert np.isnan(p[2])


def test_equivalence_is_the_ninety_percent_interval_inside_the_margin():
    """At α = 0.05 the TOST rejects exactly when the 90 % percentile interval lies inside (−m, m), up to one
    replicate either side."""
    rng = np.random.default_rng(5)
    b, m = 2000, 0.02
    for _ in range(200):
        reps = np.concatenate([[0.0], rng.normal(rng.uniform(-0.03, 0.03), rng.uniform(0.002, 0.02), b)])
        p = float(tost_p_value(reps, m))
        lo, hi = np.percentile(reps[1:], [5, 95])
        inside = -m < lo and hi < m
        if abs(lo + m) * b > 0.2 and abs(hi - m) * b > 0.2:  # away from the boundary by the grid's step
            sorted_ = np.sort(reps[1:])
            tail = max((sorted_ <= -m).sum(), (sorted_ >= m).sum())
            if abs(tail - 0.05 * (b + 1)) > 2:
                assert equivalence_verdict(p) == inside, (p, lo, hi)
    lo, hi = percentile_interval(np.zeros((10, 1)))
    assert lo[0] == hi[0] == 0


def test_an_interval_that_contains_zero_is_not_equivalence():
    """A wide interval around 0 (no difference found) is not equivalence; a tight one is."""
    wide = _normal_replicates(0.0, 0.05, 2000)
    tight = _normal_replicates(0.0, 0.005, 2000)
    assert not equivalence_verdict(float(tost_p_value(wide, 0.02)))
    assert equivalence_verdict(float(tost_p_value(tight, 0.02)))
    assert not equivalence_verdict(float("nan"))


def test_the_margin_is_checked():
    with pytest.raises(DataError, match="margin"):
        tost_p_value(np.zeros((3, 1)), 0.0)
