"""Weighted EM from sufficient statistics (glu.hmm.em), its compiled E-step (glu.hmm.online, glu.hmm._engine).

The references are independent: brute-force enumeration of every state and component path on a tiny model,
duplicated sequences for integer weights, sequences left out for weight 0, and the unweighted reference
(tested against hmmlearn in test_hmm.py) for weights of one.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from glu.errors import ModelError
from glu.hmm import TrainingConfig, loglik_many, params_bank, stack_models, train
from glu.hmm._engine.em_batch import fit_many
from glu.hmm.em import GMMHMMParams, SufficientStats, expected_stats, fit, maximise
from glu.hmm.inference import forward_backward, left_to_right_transmat
from glu.hmm.initialisation import init_left_to_right
from glu.hmm.model import GestureHMM
from glu.hmm.online import batch_stats, episode_stats

FIELDS = ("start", "trans", "counts", "first", "second", "loglik", "weight", "frames")


def walks(rng, n, lo=20, hi=40, D=3):
    return [np.cumsum(rng.normal(size=(int(rng.integers(lo, hi)), D)), axis=0) * 0.1 for _ in range(n)]


def params_of(model) -> GMMHMMParams:
    return GMMHMMParams(model.startprob, model.transmat, model.weights, model.means, model.covars)


@pytest.fixture
def problem():
    rng = np.random.default_rng(3)
    seqs = walks(rng, 6)
    return seqs, params_of(init_left_to_right(seqs, 4, 2, 0.03, seed=0))


def assert_stats_close(a: SufficientStats, b: SufficientStats, rtol=1e-10, atol=1e-10) -> None:
    for f in FIELDS:
        np.testing.assert_allclose(getattr(a, f), getattr(b, f), rtol=rtol, atol=atol, err_msg=f)


def assert_params_close(a: GMMHMMParams, b: GMMHMMParams, rtol=1e-8, atol=1e-10) -> None:
    for x, y, name in zip(a, b, GMMHMMParams._fields, strict=True):
        np.testing.assert_allclose(x, y, rtol=rtol, atol=atol, err_msg=name)


# ------------------------------------------------------------------ the E-step against brute force


def brute_force_stats(X: np.ndarray, p: GMMHMMParams) -> SufficientStats:
    """Expected statistics of one sequence by enumerating every (state, component) path."""
    T, D = X.shape
    Q, M = p.weights.shape

    def log_normal(x, mu, cov):
        d = x - mu
        return -0.5 * (D * math.log(2 * math.pi) + math.log(np.linalg.det(cov)) + d @ np.linalg.solve(cov, d))

    joint = {}
    for qs in itertools.product(range(Q), repeat=T):
        for ms in itertools.product(range(M), repeat=T):
            lp = math.log(p.startprob[qs[0]]) if p.startprob[qs[0]] > 0 else -math.inf
            for t in range(1, T):
                a = p.transmat[qs[t - 1], qs[t]]
                lp += math.log(a) if a > 0 else -math.inf
            for t in range(T):
                lp += math.log(p.weights[qs[t], ms[t]]) + log_normal(
                    X[t], p.means[qs[t], ms[t]], p.covars[qs[t], ms[t]]
                )
            joint[qs, ms] = lp
    top = max(joint.values())
    total = sum(math.exp(v - top) for v in joint.values())
    s = SufficientStats.zeros(Q, M, D)
    start, trans, counts = s.start.copy(), s.trans.copy(), s.counts.copy()
    first, second = s.first.copy(), s.second.copy()
    for (qs, ms), lp in joint.items():
        w = math.exp(lp - top) / total
        start[qs[0]] += w
        for t in range(1, T):
            trans[qs[t - 1], qs[t]] += w
        for t in range(T):
            counts[qs[t], ms[t]] += w
            first[qs[t], ms[t]] += w * X[t]
            second[qs[t], ms[t]] += w * np.outer(X[t], X[t])
    loglik = np.asarray(top + math.log(total))
    return SufficientStats(start, trans, counts, first, second, loglik, np.asarray(1.0), np.asarray(float(T)))


def test_expected_stats_equal_brute_force_enumeration():
    rng = np.random.default_rng(0)
    Q, M, D, T = 2, 2, 2, 4
    p = GMMHMMParams(
        startprob=np.array([0.7, 0.3]),
        transmat=np.array([[0.6, 0.4], [0.25, 0.75]]),
        weights=np.array([[0.4, 0.6], [0.5, 0.5]]),
        means=rng.normal(size=(Q, M, D)),
        covars=np.stack([[np.eye(D) * (0.5 + q + m) for m in range(M)] for q in range(Q)]),
    )
    X = rng.normal(size=(T, D))
    assert_stats_close(expected_stats([X], p), brute_force_stats(X, p))
    two = expected_stats([X, X[::-1]], p, [0.25, 2.0])  # and weighted: the weighted sum of both
    ref = brute_force_stats(X, p).scaled(0.25) + brute_force_stats(X[::-1], p).scaled(2.0)
    assert_stats_close(two, SufficientStats(*(getattr(ref, f) for f in FIELDS[:6]), ref.weight, ref.frames))


def test_weighted_xi_sum_is_the_weighted_sum_of_each_sequence():
    rng = np.random.default_rng(1)
    S, T, Q = 3, 7, 3
    log_b = rng.normal(size=(S, T, Q))
    lengths = np.array([7, 5, 6])
    pi, A = np.array([1.0, 0, 0]), left_to_right_transmat(Q, 0.7)
    w = np.array([0.5, 0.0, 3.0])
    _, xi_w, _ = forward_backward(log_b, lengths, pi, A, w)
    each = [forward_backward(log_b[s : s + 1], lengths[s : s + 1], pi, A)[1] for s in range(S)]
    np.testing.assert_allclose(xi_w, sum(wi * x for wi, x in zip(w, each, strict=True)), rtol=1e-12)


# ------------------------------------------------------------------ weights: duplicates, zeros, pieces


def test_integer_weights_equal_duplicated_sequences(problem):
    seqs, p0 = problem
    k = [1, 2, 0, 3, 1, 2]
    dup = [x for x, n in zip(seqs, k, strict=True) for _ in range(n)]
    assert_stats_close(expected_stats(seqs, p0, k), expected_stats(dup, p0))
    a, b = fit(seqs, p0, 15, 1e-9, 0.03, weights=k), fit(dup, p0, 15, 1e-9, 0.03)
    assert len(a.history) == len(b.history)
    np.testing.assert_allclose(a.history, b.history, rtol=1e-11)
    assert_params_close(a.params, b.params)


def test_weight_zero_equals_leaving_the_sequence_out(problem):
    seqs, p0 = problem
    w = [1.0, 0.0, 0.7, 0.0, 1.3, 1.0]
    kept = [x for x, wi in zip(seqs, w, strict=True) if wi]
    assert_stats_close(expected_stats(seqs, p0, w), expected_stats(kept, p0, [wi for wi in w if wi]))
    impossible = seqs[:2] + [np.full((10, 3), 1e6)]  # a sequence of weight 0 may even be impossible
    assert_stats_close(expected_stats(impossible, p0, [1, 1, 0]), expected_stats(seqs[:2], p0))
    a = fit(seqs, p0, 10, 1e-9, 0.03, weights=w)
    b = fit(kept, p0, 10, 1e-9, 0.03, weights=[wi for wi in w if wi])
    assert_params_close(a.params, b.params, rtol=1e-12)


def test_statistics_accumulated_in_pieces_equal_those_of_the_whole(problem):
    seqs, p0 = problem
    w = np.array([0.2, 1.0, 0.5, 2.0, 0.0, 1.5])
    whole = expected_stats(seqs, p0, w)
    pieces = expected_stats(seqs[:1], p0, w[:1])
    for i in range(1, len(seqs)):
        pieces = pieces + expected_stats(seqs[i : i + 1], p0, w[i : i + 1])
    assert_stats_close(pieces, whole)
    assert whole.weight == pytest.approx(w.sum()) and whole.frames == pytest.approx(
        w @ [len(x) for x in seqs]
    )
    assert_params_close(maximise(pieces, p0, 0.03), maximise(whole, p0, 0.03), rtol=1e-10)


def test_the_fast_weighted_em_equals_the_reference_for_every_covariance_update(problem):
    """The one fast EM (a batch of one, and the same model twice in a batch) against glu.hmm.em.fit."""
    seqs, p0 = problem
    w = np.array([0.3, 1.0, 0.0, 2.0, 1.0, 0.5])
    for cov in ("map", "ml"):
        a = fit(seqs, p0, 25, 1e-7, 0.03, cov, 0.01, weights=w)
        for b in fit_many([(seqs, p0), (seqs[::-1], p0)], 25, 1e-7, 0.03, cov, 0.01, weights=[w, w[::-1]]):
            assert len(a.history) == len(b.history), cov
            np.testing.assert_allclose(a.history, b.history, rtol=1e-10, err_msg=cov)
            assert_params_close(a.params, b.params)


def test_weighted_em_never_decreases_its_objective():
    rng = np.random.default_rng(7)
    seqs = walks(rng, 8)
    w = rng.uniform(0.05, 2.0, size=8)
    p0 = params_of(init_left_to_right(seqs[:3], 4, 2, 0.01, seed=1))  # a poor start: many EM steps
    ml = fit(seqs, p0, 40, -np.inf, covariance="ml", covar_floor=0.0, weights=w)  # exact EM
    assert np.all(np.diff(ml.history) >= -1e-8 * np.abs(ml.history[:-1]))
    assert ml.history[-1] > ml.history[0]

    # MAP covariances: the weighted log-likelihood plus the covariance prior's log-density never decreases
    reg = 0.03

    def objective(p: GMMHMMParams) -> float:
        ll = float(expected_stats(seqs, p, w).loglik)
        inv = np.linalg.inv(p.covars)
        logdet = np.linalg.slogdet(p.covars)[1]
        return ll + float(np.sum(-0.5 * logdet - 0.5 * reg * np.trace(inv, axis1=-2, axis2=-1)))

    p, values = p0, []
    for _ in range(25):
        p = maximise(expected_stats(seqs, p, w), p, reg)
        values.append(objective(p))
    assert np.all(np.diff(values) >= -1e-8 * np.abs(values[:-1]))


def test_the_m_step_keeps_left_to_right_zeros_and_normalised_rows(problem):
    seqs, p0 = problem
    p = maximise(expected_stats(seqs, p0, np.linspace(0.1, 1, 6)), p0, 0.03)
    assert np.all(p.transmat[np.tril_indices(4, -1)] == 0) and np.all(p.startprob[1:] == 0)
    np.testing.assert_allclose(p.transmat.sum(axis=1), 1.0)
    np.testing.assert_allclose(p.weights.sum(axis=1), 1.0)
    assert np.all(np.linalg.eigvalsh(p.covars) > 0)


def test_bad_weights_are_refused_in_one_line(problem):
    seqs, p0 = problem
    with pytest.raises(ModelError, match="6 weights"):
        expected_stats(seqs, p0, [1.0, 2.0])
    with pytest.raises(ModelError, match="finite and ≥ 0"):
        expected_stats(seqs, p0, [1, 1, 1, -1, 1, 1])
    with pytest.raises(ModelError, match="positive weight"):
        fit(seqs, p0, 5, 1e-3, weights=np.zeros(6))
    with pytest.raises(ModelError, match="positive weight"):
        fit_many([(seqs, p0)], 5, 1e-3, weights=[np.zeros(6)])


# ------------------------------------------------------------------ many models, one sequence


def test_the_many_model_e_step_equals_the_reference_for_each_model():
    rng = np.random.default_rng(5)
    models = [params_of(init_left_to_right(walks(rng, 4, 30, 31), 5, 2, 0.03, seed=k)) for k in range(4)]
    stack = GMMHMMParams(*(np.stack(a) for a in zip(*models, strict=True)))
    X = walks(rng, 1, 45, 46)[0]
    w = np.array([1.0, 0.4, 0.0, 2.5])
    bank, _ = episode_stats(X, stack, w)
    for k, m in enumerate(models):
        ref = expected_stats([X], m, [w[k]])
        for f in FIELDS:
            np.testing.assert_allclose(getattr(bank, f)[k], getattr(ref, f), rtol=1e-10, atol=1e-9, err_msg=f)
    _, loglik = episode_stats(X, stack)
    np.testing.assert_allclose(loglik, [expected_stats([X], m).loglik for m in models], rtol=1e-12)


def test_the_many_model_e_step_survives_underflow_in_the_log_domain():
    rng = np.random.default_rng(6)
    Q, D = 3, 3
    tight = GMMHMMParams(
        np.array([1.0, 0, 0]),
        left_to_right_transmat(Q, 0.8),
        np.ones((Q, 1)),
        np.zeros((Q, 1, D)) + np.arange(Q)[:, None, None] * 40.0,  # far-apart states: scaled mass underflows
        np.tile(np.eye(D) * 1e-3, (Q, 1, 1, 1)),
    )
    X = np.concatenate([np.zeros((5, D)), np.full((5, D), 40.0), np.full((5, D), 80.0)]) + rng.normal(
        0, 0.01, (15, D)
    )
    stack = GMMHMMParams(*(np.stack([a, a]) for a in tight))
    bank, _ = episode_stats(X, stack, np.array([1.0, 0.0]))
    ref = expected_stats([X], tight)
    np.testing.assert_allclose(bank.counts[0], ref.counts, rtol=1e-9, atol=1e-12)
    assert np.all(bank.counts[1] == 0) and bank.loglik[1] == 0


# ------------------------------------------------------------------ train(weights=)


def test_train_with_weights_learns_from_the_heavy_sequences():
    rng = np.random.default_rng(8)
    up = [np.linspace(0, 1, 30)[:, None] * [1, 2, 0] + rng.normal(0, 0.02, (30, 3)) for _ in range(5)]
    down = [x[::-1] for x in up]
    config = TrainingConfig(n_states=3, n_mix=1, n_iter=50)
    model, report = train(up + down, config, weights=[1.0] * 5 + [0.0] * 5, name="up", warn=False)
    alone, _ = train(up, config, weights=[1.0] * 5, name="up", warn=False)
    assert report.n_sequences == 5
    np.testing.assert_allclose(model.means, alone.means, rtol=1e-10)
    assert model.loglik(up[0]) > model.loglik(down[0]) + 10
    bank = train(
        {"up": up + down, "down": up + down},
        config,
        weights={"up": [1] * 5 + [0.01] * 5, "down": [0.01] * 5 + [1] * 5},
        warn=False,
    )
    assert bank["down"].model.name == "down" and bank["down"].model.loglik(down[1]) > bank[
        "down"
    ].model.loglik(up[1])


def test_train_with_weights_refuses_what_it_cannot_do(problem):
    seqs, _ = problem
    with pytest.raises(ModelError, match="glu's recipe"):
        train(seqs, TrainingConfig(recipe="mixsplit"), weights=[1.0] * 6)
    with pytest.raises(ModelError, match="weight 0"):
        train(seqs, TrainingConfig(n_states=2, n_mix=1), weights=[0.0] * 6)
    with pytest.raises(ModelError, match="finite and ≥ 0"):
        train(seqs, TrainingConfig(n_states=2, n_mix=1), weights=[1, 1, 1, 1, 1, np.nan])


def test_the_compiled_weighted_e_step_equals_the_reference(problem):
    seqs, p0 = problem
    w = np.array([0.3, 1.0, 0.0, 2.0, 1.0, 0.5])
    assert_stats_close(batch_stats(seqs, p0, w), expected_stats(seqs, p0, w))
    assert_stats_close(batch_stats(seqs, p0, np.zeros(6)), SufficientStats.zeros(4, 2, 3))


def test_weighted_training_goes_on_from_a_given_model():
    rng = np.random.default_rng(9)
    seqs = walks(rng, 6)
    config = TrainingConfig(n_states=3, n_mix=1, n_iter=3, tol=1e-12)
    w = np.linspace(0.2, 1.0, 6)
    first, _ = train(seqs, config, weights=w, warn=False)
    more, report = train(seqs, config, weights=w, warn=False, start=first)
    ref = fit(seqs, params_of(first), 3, -np.inf, 0.03, weights=w)  # three more iterations by hand
    np.testing.assert_allclose(more.means, ref.params.means, rtol=1e-9)
    assert report.history[0] == pytest.approx(float(expected_stats(seqs, params_of(first), w).loglik))
    with pytest.raises(ModelError, match="weights="):
        train(seqs, config, start=first)


def test_the_many_model_scores_equal_the_recognisers_scores():
    rng = np.random.default_rng(10)
    for M in (1, 2):  # a bank of equal shapes: the mixtures of one size
        same = [init_left_to_right(walks(rng, 4, 30, 31), 5, M, 0.03, seed=k) for k in range(3)]
        stack = GMMHMMParams(*(np.stack([getattr(m, f) for m in same]) for f in GMMHMMParams._fields))
        seqs = walks(rng, 5, 10, 50)
        np.testing.assert_allclose(
            loglik_many(params_bank(stack), seqs), loglik_many(stack_models(same), seqs), rtol=1e-10
        )


# ------------------------------------------------------------------ online stepwise EM (glu.hmm.online)


def test_online_stepwise_em_equals_the_formula_on_the_reference_e_step():
    """OnlineModels: η = w / W^α, s ← (1 − η) s + η s_episode, then the M-step of W · s — written out here
    with the reference E-step (glu.hmm.em.expected_stats) and maximise."""
    from glu.hmm.online import OnlineModels, first_model

    rng = np.random.default_rng(11)
    first, episodes = walks(rng, 3), walks(rng, 4)
    config = TrainingConfig(n_states=3, n_mix=2, n_iter=4)
    models = OnlineModels.empty((2, 2), config, n_features=3, step=0.7)
    params, stats = first_model(first, np.array([1.0, 0.5, 1.0]), config, seed=2)
    assert_stats_close(stats, expected_stats(first, params, [1.0, 0.5, 1.0]))
    models.start((1, 0), params, stats)
    assert models.exists.tolist() == [[False, False], [True, False]] and models.total[1, 0] == 2.5
    mean, total, p = stats.scaled(1 / 2.5), 2.5, params
    for X, w in zip(episodes, (0.3, 1.0, 0.8, 2.0), strict=True):
        unit, loglik = models.estep(X, (np.array([1]), np.array([0])))
        ref = expected_stats([X], p)
        assert_stats_close(unit.take(0), ref)
        assert loglik[0] == pytest.approx(float(ref.loglik), rel=1e-12)
        models.update((np.array([1]), np.array([0])), unit, np.array([w]), 0.03)
        total += w
        eta = min(1.0, w / total**0.7)
        mean = mean.scaled(1 - eta) + ref.scaled(eta)
        p = maximise(mean.scaled(total), p, 0.03, "map")
        assert_params_close(models.models((1, 0)), p)
    assert models.total[1, 0] == pytest.approx(total)
    np.testing.assert_allclose(
        models.loglik(episodes, (np.array([1]), np.array([0])))[:, 0],
        [GestureHMM(*p).loglik(X) for X in episodes],
        rtol=1e-10,
    )


def test_forward_backward_of_one_frame_whose_reachable_emission_underflows():
    """One frame, the start state's emission e⁻¹⁰⁰⁰ against the other's 1: the scaled mass of frame 1
    underflows and the log domain gives log L = −1000 exactly (without a warning: the scaled recursion
    stops before dividing by it); a single frame has no transition."""
    import warnings

    log_b = np.array([[[-1000.0, 0.0]]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gamma, xi_sum, loglik = forward_backward(
            log_b, np.array([1]), np.array([1.0, 0.0]), np.array([[0.5, 0.5], [0.0, 1.0]])
        )
    assert loglik[0] == -1000.0
    np.testing.assert_array_equal(gamma, [[[1.0, 0.0]]])
    np.testing.assert_array_equal(xi_sum, np.zeros((2, 2)))
