"""The streaming Poisson bootstrap: estimates equal direct means, intervals match closed forms, pairs are
paired."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.stats import accumulate, clopper_pearson, poisson_weights, seed_counts, two_level_sums, verdict
from glu.studies.corpus_evaluation.evaluation import EvaluationSettings, statistic_columns
from glu.studies.corpus_evaluation.intervals import metrics, paired_differences, reliability

SETTINGS = EvaluationSettings(
    fractions=(1.0,), strategies=("network", "hard", "virtual"), bins=4, bootstrap=400
)


def fake_statistics(rng, n):
    """Per-episode statistics for SETTINGS' columns: random predictions, their true metrics."""
    cols = statistic_columns(SETTINGS)
    X = np.zeros((n, len(cols)))
    X[:, 0] = 1.0
    truth = {}
    for (target, strategy), g in cols.iloc[1:].groupby(["target", "strategy"], sort=False):
        if target == "words":
            X[:, g.index] = rng.random((n, len(g)))
            continue
        p = rng.dirichlet(np.ones(3) * (3.0 if strategy == "virtual" else 1.0), size=n)
        y = rng.integers(0, 3, n)
        top = p.argmax(1)
        conf = p.max(1)
        vals = {
            "correct": (top == y) * 1.0,
            "log_loss": -np.log(p[np.arange(n), y]),
            "brier": ((p - np.eye(3)[y]) ** 2).sum(1),
        }
        b = np.minimum((conf * SETTINGS.bins).astype(int), SETTINGS.bins - 1)
        for k, r in g.iterrows():
            if r.bin < 0:
                X[:, k] = vals[r.stat]
            else:
                on = b == r.bin
                X[:, k] = on * {"bin_n": 1.0, "bin_confidence": conf, "bin_correct": vals["correct"]}[r.stat]
        truth[(target, strategy)] = (vals, conf, b)
    return cols, X, truth


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(0)
    n = 3000
    cols, X, truth = fake_statistics(rng, n)
    W = poisson_weights(n, SETTINGS.bootstrap, np.random.default_rng(1))
    S = accumulate([X[:, :500], X[:, 500:]], W)
    frame = pd.DataFrame(S, columns=[f"s{j}" for j in range(len(cols))])
    frame.insert(0, "replicate", np.arange(len(S)))
    return cols, X, truth, frame, n


def test_estimates_are_the_direct_means_and_ece(data):
    cols, X, truth, frame, n = data
    m = metrics(frame, cols, []).set_index(["target", "strategy", "metric"])
    for (target, strategy), (vals, conf, b) in truth.items():
        for stat, metric in (("correct", "accuracy"), ("log_loss", "log_loss"), ("brier", "brier")):
            assert m.loc[(target, strategy, metric), "estimate"] == pytest.approx(
                vals[stat].mean(), rel=1e-12
            )
        if target == "effect":
            ece = (
                sum(abs(vals["correct"][b == k].sum() - conf[b == k].sum()) for k in range(SETTINGS.bins)) / n
            )
            assert m.loc[(target, strategy, "ece"), "ece_plugin"] == pytest.approx(ece, rel=1e-12)
    assert (m.n_episodes == n).all()


def test_the_ece_is_bias_corrected_and_inside_its_interval(data):
    """The ECE's replicates, recomputed here from the bootstrap sums, give Efron's correction 2θ̂ − mean(θ*)
    and the basic interval [2θ̂ − q97.5, 2θ̂ − q2.5]; for a well-calibrated predictor the plug-in estimate
    may lie below its replicates' percentile interval, the corrected one lies inside its own."""
    cols, X, truth, frame, n = data
    m = metrics(frame, cols, []).set_index(["target", "strategy", "metric"])
    S = frame.sort_values("replicate")[[f"s{j}" for j in range(len(cols))]].to_numpy()
    for (target, strategy), _ in truth.items():
        if target != "effect":
            continue
        g = cols[(cols.target == target) & (cols.strategy == strategy) & (cols["bin"] >= 0)]
        conf = S[:, g.index[g.stat == "bin_confidence"]]
        corr = S[:, g.index[g.stat == "bin_correct"]]
        ece = np.abs(corr - conf).sum(axis=1) / S[:, 0]
        lo, hi = np.percentile(ece[1:], [2.5, 97.5])
        row = m.loc[(target, strategy, "ece")]
        assert row.estimate == pytest.approx(max(0.0, 2 * ece[0] - ece[1:].mean()), rel=1e-9)
        assert (row.ci_low, row.ci_high) == pytest.approx((max(0, 2 * ece[0] - hi), max(0, 2 * ece[0] - lo)))
        assert row.ci_low <= row.estimate <= row.ci_high


def test_interval_width_matches_the_normal_approximation(data):
    """For a mean of n i.i.d. values the 95 % interval is about ±1.96 σ/√n."""
    cols, X, truth, frame, n = data
    m = metrics(frame, cols, []).set_index(["target", "strategy", "metric"])
    for (target, strategy), (vals, _, _) in truth.items():
        for stat, metric in (("correct", "accuracy"), ("brier", "brier")):
            row = m.loc[(target, strategy, metric)]
            width = 2 * 1.96 * vals[stat].std(ddof=1) / np.sqrt(n)
            assert row.ci_high - row.ci_low == pytest.approx(width, rel=0.2)
            assert row.ci_low < row.estimate < row.ci_high


def test_paired_differences_are_paired(data):
    cols, X, truth, frame, n = data
    d = paired_differences(frame, cols, []).set_index(["target", "metric", "strategy", "baseline"])
    row = d.loc[("action", "accuracy", "virtual", "hard")]
    diff = truth[("action", "virtual")][0]["correct"] - truth[("action", "hard")][0]["correct"]
    assert row.difference == pytest.approx(diff.mean(), rel=1e-12)
    # paired: the interval is that of the mean of per-episode differences
    assert row.ci_high - row.ci_low == pytest.approx(2 * 1.96 * diff.std(ddof=1) / np.sqrt(n), rel=0.2)
    assert set(d.reset_index().baseline) <= {"network", "hard"}


def test_a_strategy_against_itself_differs_by_nothing():
    cols = statistic_columns(
        EvaluationSettings(fractions=(1.0,), strategies=("hard", "virtual"), bins=2, bootstrap=50)
    )
    rng = np.random.default_rng(2)
    X = rng.random((200, len(cols)))
    for target in ("action", "effect", "words"):
        a = cols.index[(cols.target == target) & (cols.strategy == "hard")]
        b = cols.index[(cols.target == target) & (cols.strategy == "virtual")]
        X[:, b] = X[:, a]
    S = accumulate([X], poisson_weights(200, 50, rng))
    frame = pd.DataFrame(S, columns=[f"s{j}" for j in range(len(cols))]).assign(replicate=np.arange(51))
    d = paired_differences(frame, cols, [])
    assert (d.difference.abs() < 1e-12).all() and (d.ci_low.abs() < 1e-12).all() and not d.better.any()


def test_groups_pool_conditions_by_summing(data):
    cols, X, truth, frame, n = data
    two = pd.concat([frame.assign(noise=0.0), frame.assign(noise=0.1)], ignore_index=True)
    by = metrics(two, cols, ["noise"])
    pooled = metrics(two, cols, [])
    assert set(by.noise) == {0.0, 0.1}
    np.testing.assert_allclose(pooled.estimate, by[by.noise == 0.0].estimate.to_numpy())
    assert (pooled.n_episodes == 2 * n).all()


def test_reliability_bins(data):
    cols, X, truth, frame, n = data
    r = reliability(frame, cols, [])
    assert set(r.strategy) == {"network", "hard", "virtual"} and set(r.target) == {"action", "effect"}
    for (target, strategy), g in r.groupby(["target", "strategy"]):
        vals, conf, b = truth[(target, strategy)]
        assert g.n.sum() == n
        k = 2
        row = g[g.bin == k].iloc[0]
        assert row.confidence == pytest.approx(conf[b == k].mean()) and row.accuracy == pytest.approx(
            vals["correct"][b == k].mean()
        )
        assert (row.lower, row.upper) == (0.5, 0.75)


def test_no_group_no_bins_and_too_few_sums(data):
    """Sums with no row for a kept factor give an empty table with the columns; statistics without
    calibration bins give no reliability rows; sums of fewer statistics than the settings have are refused."""
    from glu.errors import DataError
    from glu.studies.corpus_evaluation.intervals import metric_values

    cols, X, truth, frame, n = data
    empty = metrics(frame.assign(noise=0.0).iloc[:0], cols, ["noise"])
    assert empty.empty and list(empty.columns[:4]) == ["noise", "target", "strategy", "fraction"]
    unbinned = reliability(frame, cols.assign(bin=-1), [])
    assert unbinned.empty and list(unbinned.columns[-3:]) == ["n", "confidence", "accuracy"]
    with pytest.raises(DataError, match=f"5 sums for {len(cols)} statistics: the chunks do not match"):
        metric_values(np.zeros((1, 5)), cols)


# ------------------------------------------------------------------ two levels: seeds, then episodes


def test_seed_counts_resample_the_seeds():
    c = seed_counts(7, 500, np.random.default_rng(0))
    assert c.shape == (501, 7) and (c[0] == 1).all() and (c.sum(axis=1) == 7).all()
    assert abs(c[1:].mean() - 1.0) < 0.05 and (c[1:] == 0).any() and (c[1:] >= 2).any()


def test_one_seed_is_the_one_level_bootstrap():
    a = poisson_weights(50, 30, np.random.default_rng(3))
    b = poisson_weights(50, 30, np.random.default_rng(3), counts=np.ones(31))
    np.testing.assert_array_equal(a, b)
    assert (seed_counts(1, 30, np.random.default_rng(0)) == 1).all()


def seeds_data(rng):
    """Items of 6 seeds whose means differ (a seed effect) and whose items vary (an episode effect)."""
    return [
        rng.normal(loc, 1.0, size=(n, 1))
        for loc, n in zip((0, 1, 3, 0.5, 2, 1.5), (40, 60, 50, 45, 55, 50), strict=True)
    ]


def test_two_level_variance_equals_the_closed_form():
    """Var(Σ_k Σ_e w x) = Σ_k S_k² − (Σ_k S_k)²/K + Σ_k Q_k for multinomial seeds and Poisson episodes."""
    data = seeds_data(np.random.default_rng(1))
    sums = two_level_sums(data, 40000, np.random.default_rng(2))[:, 0]
    S = np.array([x.sum() for x in data])
    Q = np.array([(x**2).sum() for x in data])
    expected = (S**2).sum() - S.sum() ** 2 / len(S) + Q.sum()
    assert sums[0] == pytest.approx(S.sum(), rel=1e-12)
    assert sums[1:].var() == pytest.approx(expected, rel=0.04)
    assert sums[1:].mean() == pytest.approx(S.sum(), rel=0.02)


def test_two_level_interval_equals_a_brute_force_hierarchical_bootstrap():
    """The pooled mean's percentile interval, against resampling seeds and then each copy's items
    explicitly."""
    rng = np.random.default_rng(4)
    data = seeds_data(rng)
    ones = [np.hstack([np.ones((len(x), 1)), x]) for x in data]
    sums = two_level_sums(ones, 6000, np.random.default_rng(5))
    fast = sums[1:, 1] / sums[1:, 0]
    brute = []
    for _ in range(6000):
        picked = rng.integers(0, len(data), len(data))
        items = [data[k][rng.integers(0, len(data[k]), len(data[k]))] for k in picked]
        brute.append(np.concatenate(items).mean())
    lo_f, hi_f = np.percentile(fast, [2.5, 97.5])
    lo_b, hi_b = np.percentile(brute, [2.5, 97.5])
    width = hi_b - lo_b
    assert abs(lo_f - lo_b) < 0.08 * width and abs(hi_f - hi_b) < 0.08 * width
    assert sums[0, 1] / sums[0, 0] == pytest.approx(np.concatenate(data).mean(), rel=1e-12)


def test_the_seed_level_widens_the_interval():
    """Seeds that disagree give a wider interval than their pooled episodes resampled alone."""
    data = seeds_data(np.random.default_rng(6))
    ones = [np.hstack([np.ones((len(x), 1)), x]) for x in data]
    two = two_level_sums(ones, 2000, np.random.default_rng(7))
    one = accumulate([np.vstack(ones)], poisson_weights(sum(map(len, ones)), 2000, np.random.default_rng(7)))
    w2 = np.diff(np.percentile(two[1:, 1] / two[1:, 0], [2.5, 97.5]))[0]
    w1 = np.diff(np.percentile(one[1:, 1] / one[1:, 0], [2.5, 97.5]))[0]
    assert w2 > 2 * w1


@pytest.mark.parametrize("k,n", [(0, 11), (3, 11), (8, 11), (11, 11), (1, 2), (2, 2), (47, 120)])
def test_clopper_pearson_matches_scipy_exact_interval(k, n):
    from scipy.stats import binomtest

    ref = binomtest(k, n).proportion_ci(confidence_level=0.95, method="exact")
    lo, hi = clopper_pearson(k, n)
    assert lo == pytest.approx(ref.low, abs=1e-12) and hi == pytest.approx(ref.high, abs=1e-12)
    if k == 0:
        assert hi == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-12)  # closed form
    if k == n:
        assert lo == pytest.approx(0.025 ** (1 / n), rel=1e-12)


def test_verdicts():
    assert verdict(0.01, 0.2) == "better" and verdict(0.01, 0.2, higher_is_better=False) == "worse"
    assert verdict(-0.2, -0.01) == "worse" and verdict(-0.2, -0.01, False) == "better"
    assert verdict(-0.1, 0.1) == "no difference" and verdict(np.nan, 0.1) == "no difference"
