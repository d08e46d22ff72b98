"""The streaming Poisson bootstrap: estimates equal direct means, intervals match closed forms, pairs are paired."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.experiments.evaluation import EvaluationSettings, statistic_columns
from glu.experiments.intervals import accumulate, metrics, paired_differences, poisson_weights, reliability

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
        if target == "description":
            X[:, g.index] = rng.random((n, len(g))) < 0.6
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
            assert m.loc[(target, strategy, "ece"), "estimate"] == pytest.approx(ece, rel=1e-12)
    assert (m.n_episodes == n).all()


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
    for target in ("action", "effect", "description"):
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
    assert set(r.strategy) == {"network", "hard", "virtual"}
    for strategy, g in r.groupby("strategy"):
        vals, conf, b = truth[("effect", strategy)]
        assert g.n.sum() == n
        k = 2
        row = g[g.bin == k].iloc[0]
        assert row.confidence == pytest.approx(conf[b == k].mean()) and row.accuracy == pytest.approx(
            vals["correct"][b == k].mean()
        )
        assert (row.lower, row.upper) == (0.5, 0.75)
