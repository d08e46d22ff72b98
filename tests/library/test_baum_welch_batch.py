"""The one fast EM (glu.hmm._engine.em_batch) against the readable reference for each model alone
(glu.hmm.em.fit, itself tested against hmmlearn and brute force in test_hmm.py)."""

from __future__ import annotations

import numpy as np
import pytest

from glu.hmm import em as bw
from glu.hmm import inference
from glu.hmm._engine.em_batch import fit_many
from glu.hmm._engine.kernels import forward_backward_scaled
from glu.hmm.initialisation import init_left_to_right


@pytest.fixture(scope="module")
def corpus():
    from glu.gestures.corpus import synthetic_corpus

    return synthetic_corpus(8, seed=5, actions=("grasp", "tap", "touch"))


def _start(seqs, Q, M, seed=0, reg=1e-3):
    m = init_left_to_right(seqs, Q, M, reg, seed)
    return bw.GMMHMMParams(m.startprob, m.transmat, m.weights, m.means, m.covars)


def _assert_same(got, ref):
    assert len(got) == len(ref)
    for g, r in zip(got, ref, strict=True):
        assert len(g.history) == len(r.history)
        np.testing.assert_allclose(g.history, r.history, rtol=1e-10)
        for name, a, b in zip(bw.GMMHMMParams._fields, g.params, r.params, strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-12, err_msg=name)


@pytest.mark.parametrize("covariance", bw.COVARIANCES)
def test_fit_many_equals_fitting_each_model_alone(corpus, covariance):
    """Models with different numbers and lengths of sequences, and different shapes (grouped): same
    iterations, histories and parameters as one fit per model; models stop at different iterations."""
    problems, tols = [], []
    for i, action in enumerate(("grasp", "tap", "touch")):
        seqs = [s.xyz for s in corpus if s.action == action]
        for drop, (Q, M) in enumerate([(6, 3), (6, 3), (4, 2), (6, 3)]):
            subset = seqs[drop : len(seqs) - i]
            problems.append((subset, _start(subset, Q, M, seed=drop)))
            tols.append(1e-3 * sum(len(x) for x in subset) * (1 + drop))
    n_iter, floor = 25, 0.0  # plain ML for "ml": its log-likelihood never decreases, so EM runs a while
    ref = [bw.fit(s, p, n_iter, t, 1e-3, covariance, floor) for (s, p), t in zip(problems, tols, strict=True)]
    assert len({len(r.history) for r in ref}) > 1  # the models do stop at different iterations
    _assert_same(fit_many(problems, n_iter, tols, 1e-3, covariance, floor), ref)


def test_fit_many_stops_at_n_iter_and_keeps_the_input_order(corpus):
    seqs = [s.xyz for s in corpus if s.action == "tap"]
    problems = [
        (seqs[:3], _start(seqs[:3], 3, 1)),
        (seqs[3:], _start(seqs[3:], 5, 2)),
        (seqs, _start(seqs, 3, 1)),
    ]
    got = fit_many(problems, 4, 1e-300, 1e-3)
    assert [len(r.history) for r in got] == [4, 4, 4]
    _assert_same(got, [bw.fit(s, p, 4, 1e-300, 1e-3) for s, p in problems])


def _underflowing_problem():
    """A left-to-right model that must start in state 0, and sequences whose first frame sits on state 1's
    mean, 85 standard deviations from state 0's: the scaled first frame underflows (e^-3600)."""
    rng = np.random.default_rng(2)
    seqs = [
        np.vstack([[[60.0, 60.0]], rng.normal(0.0, 1.0, (n, 2)), rng.normal(60.0, 1.0, (n, 2))])
        for n in (6, 9)
    ]
    init = bw.GMMHMMParams(
        np.array([1.0, 0.0]),
        np.array([[0.8, 0.2], [0.0, 1.0]]),
        np.ones((2, 1)),
        np.array([[[0.0, 0.0]], [[60.0, 60.0]]]),
        np.tile(np.eye(2), (2, 1, 1, 1)),
    )
    return seqs, init


def test_fit_many_redoes_only_the_underflowing_sequences_in_the_log_domain(monkeypatch):
    from glu.hmm._engine import em_batch as baum_welch_batch

    seqs, init = _underflowing_problem()
    log_b = np.array([[[-1800.0, 0.0], [0.0, -5.0]]])
    gamma, xi, ll, ok = forward_backward_scaled(
        log_b, np.array([2]), init.startprob[None], init.transmat[None]
    )
    assert not ok[0]  # the scaled pass reports the underflow; the log domain has it finite
    assert np.isfinite(
        inference.forward_backward_log(log_b, np.array([2]), init.startprob, init.transmat)[2]
    ).all()
    rng = np.random.default_rng(3)
    normal = [rng.normal(size=(n, 2)) + np.linspace(0, 3, n)[:, None] for n in (12, 20, 15)]
    problems = [(normal, _start(normal, 2, 1)), (seqs, init), (normal[1:], _start(normal[1:], 2, 1))]
    with np.errstate(all="ignore"):  # fit's scaled pass underflows before it turns to the log domain
        ref = [bw.fit(s, p, 6, 1e-300, 1e-2) for s, p in problems]
    assert np.isfinite(ref[1].history).all()
    redone = []

    def log_domain(log_b, lengths, startprob, transmat):
        redone.append(sorted(lengths.tolist()))
        return inference.forward_backward_log(log_b, lengths, startprob, transmat)

    monkeypatch.setattr(baum_welch_batch, "forward_backward_log", log_domain)
    _assert_same(fit_many(problems, 6, 1e-300, 1e-2), ref)
    lengths = {len(x) + 0 for x in seqs}
    assert redone and all(len(r) == 1 and r[0] in lengths for r in redone)  # that model's sequences, alone


def test_the_compiled_forward_backward_equals_one_model_at_a_time():
    """Per-sequence parameters: each sequence as forward_backward (brute-force-tested) gives it alone."""
    rng = np.random.default_rng(7)
    S, T, Q = 5, 9, 3
    lengths = np.array([9, 7, 7, 3, 1])
    log_b = rng.normal(size=(S, T, Q)) * 3
    pi = rng.dirichlet(np.ones(Q), size=S)
    A = rng.dirichlet(np.ones(Q), size=(S, Q))
    gamma, xi, ll, ok = forward_backward_scaled(log_b, lengths, pi, A)
    assert ok.all()
    for s in range(S):
        g, x, lls = inference.forward_backward(
            log_b[s : s + 1, : lengths[s]], lengths[s : s + 1], pi[s], A[s]
        )
        np.testing.assert_allclose(ll[s], lls[0], rtol=1e-12)
        np.testing.assert_allclose(gamma[s, : lengths[s]], g[0], atol=1e-12)
        np.testing.assert_allclose(xi[s], x, atol=1e-12)
        assert (gamma[s, lengths[s] :] == 0).all()


# --- training several models at once, against the one-model path -----------------------------------


def _assert_same_models(got, ref):
    for (m, r), (m_ref, r_ref) in zip(got, ref, strict=True):
        key = ("action", "n_sequences", "n_frames", "n_iter", "converged", "tol", "max_iter")
        assert [getattr(r, k) for k in key] == [getattr(r_ref, k) for k in key]
        np.testing.assert_allclose(r.history, r_ref.history, rtol=1e-10)
        assert r.final_loglik == pytest.approx(r_ref.final_loglik, rel=1e-10)
        for a in ("startprob", "transmat", "weights", "means", "covars"):
            np.testing.assert_allclose(getattr(m, a), getattr(m_ref, a), rtol=1e-8, atol=1e-12, err_msg=a)


def test_training_many_models_equals_training_each_alone(corpus):
    """glu.hmm.train on a mapping (batched EM) against glu.hmm.train on each model's list (the reference
    EM)."""
    from glu.hmm import TrainingConfig, train

    sets = [[s.xyz for s in corpus if s.action == a][i:] for a in ("grasp", "tap") for i in (0, 2)]
    names, seeds = ["g0", "g2", "t0", "t2"], [0, 1, 2, 0]
    config = TrainingConfig(n_states=5, n_mix=2, n_iter=30, tol=1e-4, covar_reg=0.03)
    ref = [
        train(s, config, seed=sd, name=nm, warn=False) for s, sd, nm in zip(sets, seeds, names, strict=True)
    ]
    batch = train(
        dict(zip(names, sets, strict=True)), config, seed=dict(zip(names, seeds, strict=True)), warn=False
    )
    _assert_same_models(list(batch.values()), ref)


def test_mixsplit_many_models_equals_mixsplit_each_alone(corpus):
    from glu.hmm import TrainingConfig
    from glu.hmm.mixsplit import train_batch, train_one

    sets = [[s.xyz for s in corpus if s.action == a][i:] for a in ("tap", "touch") for i in (0, 3)]
    config = TrainingConfig(n_states=4, n_mix=3, n_iter=15, recipe="mixsplit")
    ref = [train_one(s, config, name=f"m{i}", warn=False) for i, s in enumerate(sets)]
    got = train_batch(sets, config, names=[f"m{i}" for i in range(len(sets))], warn=False)
    _assert_same_models([g[:2] for g in got], [r[:2] for r in ref])
    for g, r in zip(got, ref, strict=True):
        assert [len(h) for h in g[2]] == [len(h) for h in r[2]]  # every stage ran as many iterations


def test_training_errors_name_the_model_as_one_model_training_does(corpus):
    from glu.errors import DataError
    from glu.hmm import TrainingConfig, train

    ok = [s.xyz for s in corpus if s.action == "tap"]
    with pytest.raises(DataError, match="'short'.*too few"):
        train({"tap": ok, "short": [ok[0][:3]]}, TrainingConfig(n_states=6, n_mix=3))


def test_mixture_posteriors_are_scipys_logsumexp_and_softmax():
    """The compiled mixture step against SciPy, with components of weight 0 (−∞) and huge magnitudes."""
    from scipy.special import logsumexp, softmax

    from glu.hmm._engine.kernels import mixture_posteriors

    rng = np.random.default_rng(5)
    lc = rng.normal(0, 50, size=(3, 40, 6, 3)) - 1e3 * rng.random((3, 40, 6, 1))
    lc[0, :, 2, 1] = -np.inf  # a component of weight 0
    log_b, post = mixture_posteriors(lc)
    np.testing.assert_allclose(log_b, logsumexp(lc, axis=3), rtol=1e-13)
    np.testing.assert_allclose(post, softmax(lc, axis=3), rtol=1e-12, atol=1e-300)
    assert (post[0, :, 2, 1] == 0).all()


def test_training_reports_progress_while_the_models_train(corpus):
    """train(progress=…) is told how many models finished after each EM iteration: every model once."""
    from glu.hmm import TrainingConfig, train

    sets = {a: [s.xyz for s in corpus if s.action == a] for a in ("grasp", "tap", "touch")}
    for recipe in ("glu", "mixsplit"):
        calls: list[int] = []
        train(
            sets,
            TrainingConfig(n_states=3, n_mix=2, n_iter=30, recipe=recipe),
            warn=False,
            progress=calls.append,
        )
        assert sum(calls) == 3 and all(c > 0 for c in calls)
