"""Multiplicity adjustments and bootstrap p-values (glu.stats), against statsmodels, published examples and
brute force."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from glu import stats
from glu.errors import DataError
from glu.stats import adjust, adjusted_verdict, benjamini_hochberg, bootstrap_p_value, holm


def test_benjamini_hochberg_paper_example():
    """Benjamini & Hochberg (1995, §4): the 15 p-values of their example; at q = 0.05 the four smallest are
    rejected (the BH threshold's largest i with p_(i) ≤ i · 0.05 / 15 is i = 4)."""
    p = np.array(
        [0.0001, 0.0004, 0.0019, 0.0095, 0.0201, 0.0278, 0.0298, 0.0344, 0.0459, 0.3240, 0.4262, 0.5719,
         0.6528, 0.7590, 1.0000]
    )  # fmt: skip
    assert (benjamini_hochberg(p) <= 0.05).sum() == 4


def test_holm_by_definition_brute_force():
    """Holm's adjusted p-value of hypothesis i is the smallest α at which the step-down procedure rejects it;
    found here by running the procedure itself over a fine grid of α."""
    rng = np.random.default_rng(3)
    p = np.concatenate([rng.uniform(0, 0.02, 4), rng.uniform(0, 1, 6)])
    m = len(p)

    def rejected(alpha):
        out = np.zeros(m, bool)
        for j, i in enumerate(np.argsort(p)):
            if p[i] > alpha / (m - j):
                break
            out[i] = True
        return out

    grid = np.linspace(0, 1, 20001)
    smallest = np.array([grid[np.argmax([rejected(a)[i] for a in grid])] if rejected(1.0)[i] else 1.0
                         for i in range(m)])  # fmt: skip
    assert np.allclose(holm(p), np.minimum(1, smallest), atol=1e-4)


@pytest.mark.parametrize("method,name", [("holm", "holm"), ("bh", "fdr_bh")])
def test_against_statsmodels(method, name):
    multitest = pytest.importorskip("statsmodels.stats.multitest")
    rng = np.random.default_rng(0)
    for m in (1, 2, 7, 40):
        p = np.where(rng.random(m) < 0.3, rng.uniform(0, 0.01, m), rng.uniform(0, 1, m))
        p[: m // 4] = p[0]  # ties
        want = multitest.multipletests(p, method=name)[1]
        assert np.allclose(adjust(p, method), want, atol=1e-12)


def test_nan_entries_are_left_out_of_the_family():
    p = np.array([0.01, np.nan, 0.02, 0.04])
    assert np.isnan(holm(p)[1]) and np.isnan(benjamini_hochberg(p)[1])
    assert np.allclose(holm(p)[[0, 2, 3]], holm(p[[0, 2, 3]]))
    with pytest.raises(DataError, match="lie in"):
        holm(np.array([1.5]))
    with pytest.raises(DataError, match="unknown adjustment"):
        adjust(p, "bonferroni")


def test_bootstrap_p_value_counts_the_far_side():
    """A closed form: replicates −1 … 98 of a difference estimated at 50 have 2 at or below 0 (−1 and 0), so
    p = 2 (1 + 2) / 101; a null at the median gives p = 1 (capped)."""
    reps = np.concatenate([[50.0], np.arange(-1, 99, dtype=float)])
    assert bootstrap_p_value(reps) == pytest.approx(6 / 101)
    assert bootstrap_p_value(reps, null=48.5) == 1.0
    two = np.stack([reps, -reps], axis=1)
    assert np.allclose(bootstrap_p_value(two), [6 / 101, 6 / 101])
    assert np.isnan(bootstrap_p_value(np.array([1.0, np.nan, np.nan])))


def test_p_value_agrees_with_the_percentile_interval():
    """p < 0.05 exactly when the 95 % percentile interval excludes 0, up to one replicate's worth."""
    from glu.stats import interval

    rng = np.random.default_rng(1)
    for shift in np.linspace(0, 0.5, 26):
        reps = np.concatenate([[shift], rng.normal(shift, 0.1, 1999)])
        lo, hi = interval(reps)
        far = min((reps[1:] <= 0).sum(), (reps[1:] >= 0).sum())
        if far not in (49, 50):  # the boundary: a replicate either way
            assert (bootstrap_p_value(reps) < 0.05) == (lo > 0 or hi < 0)


def test_adjusted_verdict():
    assert adjusted_verdict(0.2, 0.01) == "better"
    assert adjusted_verdict(0.2, 0.01, higher_is_better=False) == "worse"
    assert adjusted_verdict(-0.2, 0.01) == "worse"
    assert adjusted_verdict(-0.2, 0.2) == "no difference"
    assert adjusted_verdict(np.nan, 0.01) == "no difference"


def test_holm_never_below_bh_and_both_above_raw():
    rng = np.random.default_rng(5)
    for _ in range(50):
        p = rng.uniform(0, 0.2, 12)
        assert (holm(p) >= benjamini_hochberg(p) - 1e-15).all()
        assert (benjamini_hochberg(p) >= p - 1e-15).all()
    for perm in itertools.permutations([0.01, 0.02, 0.03]):
        assert np.allclose(np.sort(holm(np.array(perm))), [0.03, 0.04, 0.04])


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda rng: stats.seed_counts(0, 5, rng), "at least one seed, not 0"),
        (
            lambda rng: stats.poisson_weights(4, 5, rng, counts=np.ones(5)),
            r"counts of shape \(5,\); expected \(6,\)",
        ),
        (lambda rng: stats.two_level_sums([np.ones((3, 2)), np.ones((3, 1))], 5, rng), "same statistics"),
        (lambda rng: stats.two_level_weights(2, 0, 5, rng), "needs seeds and units, got 2 and 0"),
        (lambda rng: stats.clopper_pearson(4, 3), r"k=4, n=3"),
        (lambda rng: stats.clopper_pearson(0, 0), r"k=0, n=0"),
    ],
)
def test_bootstrap_helpers_refuse_what_they_cannot_resample(call, message):
    with pytest.raises(DataError, match=message):
        call(np.random.default_rng(0))


def test_intervals_without_replicates_are_nan_of_the_statistics_shape():
    """Zero replicates (row 0, the estimate, alone): no interval, one NaN per statistic."""
    for lo, hi in (stats.percentile_interval(np.empty((0, 2, 3))), stats.interval(np.ones((1, 2, 3)))):
        assert lo.shape == hi.shape == (2, 3) and np.isnan(lo).all() and np.isnan(hi).all()
