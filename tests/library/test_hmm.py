"""Gesture HMMs against independent references: brute force, scipy log-domain forward, hmmlearn's score."""

from __future__ import annotations

import itertools
import json
import warnings

import numpy as np
import pytest
from hmm_reference import fit_hmmlearn_update, to_hmmlearn, train_hmmlearn
from scipy.io import loadmat
from scipy.special import logsumexp
from scipy.stats import multivariate_normal

from glu.errors import DataError, ModelError
from glu.gestures.recognizer import Recognizer, load_original_models, train_recognizer
from glu.hmm import HMMConvergenceWarning, TrainingConfig, train
from glu.hmm.inference import forward_curve, left_to_right_transmat, p_hmm_from_loglik
from glu.hmm.initialisation import init_left_to_right
from glu.hmm.model import GestureHMM

# --- independent references (no glu code) ----------------------------------------------------------


def ref_log_b(X, weights, means, covars):
    """log p(x_t | q) with scipy, shape (T, Q)."""
    Q, M = weights.shape
    out = np.empty((len(X), Q))
    for q in range(Q):
        comps = [
            np.log(weights[q, m]) + multivariate_normal(means[q, m], covars[q, m]).logpdf(X).reshape(-1)
            for m in range(M)
            if weights[q, m] > 0
        ]
        out[:, q] = logsumexp(comps, axis=0)
    return out


def ref_forward(X, startprob, transmat, weights, means, covars):
    """Log-domain forward algorithm with log-sum-exp; returns every prefix log-likelihood, shape (T,)."""
    lb = ref_log_b(X, weights, means, covars)
    with np.errstate(divide="ignore"):
        lpi, lA = np.log(startprob), np.log(transmat)
    la = lpi + lb[0]
    out = [logsumexp(la)]
    for t in range(1, len(X)):
        la = logsumexp(la[:, None] + lA, axis=0) + lb[t]
        out.append(logsumexp(la))
    return np.array(out)


def random_model(rng, Q=3, M=2, D=2, left_to_right=True, name=""):
    A = rng.dirichlet(np.ones(Q), size=Q)
    if left_to_right:
        A = np.triu(A)
        A /= A.sum(1, keepdims=True)
    pi = np.zeros(Q)
    pi[0] = 1.0
    if not left_to_right:
        pi = rng.dirichlet(np.ones(Q))
    w = rng.dirichlet(np.ones(M), size=Q)
    mu = rng.normal(scale=2.0, size=(Q, M, D))
    L = rng.normal(scale=0.4, size=(Q, M, D, D))
    cov = L @ np.swapaxes(L, -1, -2) + 0.2 * np.eye(D)
    return GestureHMM(pi, A, w, mu, cov, name=name)


def params(m: GestureHMM):
    return m.startprob, m.transmat, m.weights, m.means, m.covars


# --- the forward recursion ---------------------------------------------------------------------------


def test_loglik_equals_brute_force_over_state_paths():
    rng = np.random.default_rng(0)
    m = random_model(rng, Q=3, M=2, D=2, left_to_right=False)
    X = rng.normal(size=(4, 2))
    b = np.exp(ref_log_b(X, m.weights, m.means, m.covars))
    total = 0.0
    for path in itertools.product(range(3), repeat=4):
        p = m.startprob[path[0]] * b[0, path[0]]
        for t in range(1, 4):
            p *= m.transmat[path[t - 1], path[t]] * b[t, path[t]]
        total += p
    assert m.loglik(X) == pytest.approx(np.log(total), abs=1e-10)


def test_emissions_equal_scipy_mixture_densities():
    rng = np.random.default_rng(1)
    m = random_model(rng, Q=4, M=3, D=3)
    X = rng.normal(size=(20, 3))
    np.testing.assert_allclose(m.log_emission(X), ref_log_b(X, m.weights, m.means, m.covars), rtol=1e-10)


def test_prefix_curve_equals_log_domain_reference_and_hmmlearn():
    rng = np.random.default_rng(2)
    m = random_model(rng, Q=5, M=2, D=3)
    X = rng.normal(size=(30, 3))
    curve = m.loglik_curve(X)
    np.testing.assert_allclose(curve, ref_forward(X, *params(m)), rtol=1e-10, atol=1e-8)
    h = to_hmmlearn(m)
    for t in (1, 7, 30):
        assert curve[t - 1] == pytest.approx(h.score(X[:t]), abs=1e-8)


def test_forward_survives_outliers_and_underflow():
    rng = np.random.default_rng(3)
    m = random_model(rng, Q=4, M=2, D=3)
    X = rng.normal(size=(25, 3))
    X[10] = [300.0, -200.0, 150.0]  # emissions ~ exp(-1e5): every scaled emission underflows
    X[11] = [-40.0, 60.0, 0.0]
    np.testing.assert_allclose(m.loglik_curve(X), ref_forward(X, *params(m)), rtol=1e-10)
    # an unreachable state keeps a zero forward variable; hard zeros in transmat are fine
    lb = np.log(np.full((3, 2), 0.5))
    assert forward_curve(lb, np.array([1.0, 0.0]), np.array([[1.0, 0.0], [0.0, 1.0]]))[-1] == pytest.approx(
        3 * np.log(0.5)
    )


def test_p_hmm_is_a_softmax_in_the_log_domain():
    ll = np.array([-1000.0, -1001.0, -2000.0])
    p = p_hmm_from_loglik(ll)
    e = np.exp([0.0, -1.0, -1000.0])
    np.testing.assert_allclose(p, e / e.sum(), rtol=1e-12)
    assert p.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(p_hmm_from_loglik(np.zeros(4)), 0.25)


# --- the recogniser and its streaming form -------------------------------------------------------------


@pytest.fixture(scope="module")
def bank():
    rng = np.random.default_rng(4)
    return Recognizer(
        {
            "grasp": random_model(rng, Q=6, M=3, D=3, name="grasp"),
            "tap": random_model(rng, Q=4, M=1, D=3, name="tap"),  # different Q and M: padding is exercised
            "touch": random_model(rng, Q=5, M=2, D=3, name="touch"),
            "push": random_model(rng, Q=6, M=3, D=3, name="push"),
        }
    )


def test_streaming_equals_rescoring_every_prefix(bank):
    rng = np.random.default_rng(5)
    X = rng.normal(size=(40, 3)) * 1.5
    X[20] = [50.0, 0.0, -50.0]  # an outlier frame in the middle of the stream
    stream = bank.stream()
    steps = [stream.push(x) for x in X]
    hmmlearn_models = {a: to_hmmlearn(m) for a, m in bank.models.items()}
    for t in (1, 2, 20, 21, 22, 40):
        ref = np.array([hmmlearn_models[a].score(X[:t]) for a in bank.actions])
        np.testing.assert_allclose(steps[t - 1].loglik, ref, rtol=1e-9)
        np.testing.assert_allclose(steps[t - 1].p_hmm, p_hmm_from_loglik(ref), rtol=1e-9, atol=1e-300)
        assert steps[t - 1].t == t
    for t in range(1, 41):
        ref = [ref_forward(X[:t], *params(bank.models[a]))[-1] for a in ("tap",)]
        assert steps[t - 1].loglik[1] == pytest.approx(ref[0], rel=1e-10)
    np.testing.assert_allclose(np.array([s.loglik for s in steps]), bank.loglik_curve(X), rtol=1e-10)
    stream.reset()
    assert stream.push(X[0]).t == 1


def test_recognizer_outputs(bank):
    rng = np.random.default_rng(6)
    X = rng.normal(size=(15, 3))
    ll = bank.loglik(X)
    assert ll.shape == (4,)
    np.testing.assert_allclose(
        ll, [ref_forward(X, *params(bank.models[a]))[-1] for a in bank.actions], rtol=1e-10
    )
    p = bank.p_hmm(X)
    assert p.sum() == pytest.approx(1.0) and bank.classify(X) == bank.actions[int(np.argmax(p))]
    assert bank.p_hmm_curve(X).shape == (15, 4)
    with pytest.raises(DataError, match=r"shape \(n_frames, 3\)"):
        bank.loglik(np.zeros((5, 2)))
    with pytest.raises(DataError, match="no frames"):
        bank.loglik(np.zeros((0, 3)))
    with pytest.raises(DataError, match="frame 2"):
        bank.loglik(np.array([[0, 0, 0], [np.nan, 0, 0]]))
    with pytest.raises(DataError):
        bank.stream().push(np.array([1.0, np.inf, 0.0]))


def test_a_recognizer_checks_its_models_and_shows_them(bank):
    rng = np.random.default_rng(7)
    with pytest.raises(ModelError, match="a recogniser needs at least one model"):
        Recognizer({})
    with pytest.raises(ModelError, match=r"all models must have the same number of features, got \[2, 3\]"):
        Recognizer({"tap": random_model(rng, D=3), "push": random_model(rng, D=2)})
    with pytest.raises(ModelError, match="invariant features need 3-D models, these have 2 features"):
        Recognizer({"tap": random_model(rng, D=2)}, features="centred")
    assert (
        repr(bank) == "Recognizer(grasp: Q=6 M=3, tap: Q=4 M=1, touch: Q=5 M=2, push: Q=6 M=3; features raw)"
    )


def test_many_training_sets_need_as_many_seeds():
    sets = [{"tap": [np.zeros((10, 3))]}, {"tap": [np.ones((10, 3))]}]
    with pytest.raises(ModelError, match="2 training sets need as many seeds and feature sets, got 1 and 2"):
        train_recognizer(sets, seed=[0])
    with pytest.raises(ModelError, match="got 2 and 3"):
        train_recognizer(sets, features=["raw", "centred", "scaled"])


def test_save_load_round_trip_scores_identically(bank, tmp_path):
    path = bank.save(tmp_path / "rec.json")
    d = json.loads(path.read_text())
    assert d["format"] == "glu-gesture-recognizer" and d["version"] == 3
    assert d["actions"] == ["grasp", "tap", "touch", "push"]
    assert np.array(d["models"]["grasp"]["covars"]).shape == (6, 3, 3, 3)
    again = Recognizer.load(path)
    X = np.random.default_rng(7).normal(size=(33, 3))
    np.testing.assert_array_equal(again.loglik(X), bank.loglik(X))
    np.testing.assert_array_equal(again.loglik_curve(X), bank.loglik_curve(X))


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda d: d.update(format="other"), "not a glu gesture recogniser"),
        (lambda d: d.update(version=99), "format version 99"),
        (lambda d: d["actions"].append("wave"), "exactly the keys"),
        (lambda d: d["models"]["tap"].pop("means"), "missing or malformed field"),
        (lambda d: d["models"]["tap"]["transmat"][0].__setitem__(0, 5.0), "sum to one"),
        (
            lambda d: d["models"]["tap"].update(covars=[[[[1, 0, 0], [0, -1, 0], [0, 0, 1]]]] * 4),
            "positive definite",
        ),
        (lambda d: d["models"]["tap"].update(weights=[[1.0]] * 3), "shape"),
        (lambda d: d.update(config={"n_states": 0, "n_mix": 1}), "'config'.*n_states=0"),
        (lambda d: d.update(config={"states": 6}), "'config' must be a JSON object"),
    ],
)
def test_malformed_recogniser_files(bank, tmp_path, mutate, message):
    d = bank.to_dict()
    mutate(d)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(d))
    with pytest.raises(ModelError, match=message):
        Recognizer.load(path)


def test_a_recogniser_keeps_its_training_config_and_reads_version_2_files(tmp_path):
    """The settings travel whole (TrainingConfig, the file's "config"); a version-2 file, which kept them in
    its meta, is read into the same TrainingConfig."""
    from glu.gestures.corpus import synthetic_corpus

    corpus = synthetic_corpus(3, seed=2, actions=("tap", "grasp"))
    config = TrainingConfig(n_states=3, n_mix=1, n_iter=5, tol=1e-3, covar_reg=0.05)
    rec = train_recognizer(
        {a: [s.xyz for s in corpus if s.action == a] for a in ("tap", "grasp")}, config, warn=False
    )
    assert rec.config == config and "n_states" not in rec.meta
    again = Recognizer.load(rec.save(tmp_path / "r.json"))
    assert again.config == config
    old = rec.to_dict()  # as glu wrote it before the config had a key of its own
    del old["config"]
    old["version"] = 2
    old["meta"].update(recipe="glu", n_states=3, n_mix=1, n_iter=5, tol=1e-3, covar_reg=0.05, seed=0)
    (tmp_path / "v2.json").write_text(json.dumps(old))
    v2 = Recognizer.load(tmp_path / "v2.json")
    assert v2.config == config and v2.meta["n_states"] == 3
    np.testing.assert_array_equal(v2.loglik(corpus[0].xyz), rec.loglik(corpus[0].xyz))
    assert Recognizer(rec.models).config is None


def test_unreadable_recogniser_files(tmp_path):
    with pytest.raises(ModelError, match="no such"):
        Recognizer.load(tmp_path / "none.json")
    (tmp_path / "x.json").write_bytes(b"\xff\xfe not json")
    with pytest.raises(ModelError, match="not a JSON"):
        Recognizer.load(tmp_path / "x.json")


# --- training ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def corpus():
    from glu.gestures.corpus import synthetic_corpus

    return synthetic_corpus(10, seed=3, actions=("grasp", "tap", "touch"))


def test_initialisation_from_equal_time_slices():
    rng = np.random.default_rng(8)
    seqs = [rng.normal(size=(n, 3)) + np.arange(n)[:, None] / n * 10 for n in (30, 45, 60)]
    m = init_left_to_right(seqs, n_states=3, n_mix=1, covar_reg=0.03)
    for q in range(3):  # state q starts at the mean of the q-th third of every sequence
        frames = np.concatenate([X[len(X) * q // 3 : len(X) * (q + 1) // 3] for X in seqs])
        np.testing.assert_allclose(m.means[q, 0], frames.mean(axis=0), rtol=1e-10)
    assert m.is_left_to_right and m.startprob.tolist() == [1.0, 0.0, 0.0]


def test_training_keeps_the_left_to_right_structure(corpus):
    seqs = [s.xyz for s in corpus if s.action == "grasp"]
    m, report = train(
        seqs, TrainingConfig(n_states=5, n_mix=2, n_iter=15, tol=1e-6), name="grasp", warn=False
    )
    A = m.transmat
    assert np.all(np.tril(A, -1) == 0) and np.all(np.triu(A, 2) == 0)  # only stay or step right
    assert m.startprob.tolist() == [1.0, 0.0, 0.0, 0.0, 0.0]
    np.testing.assert_allclose(A.sum(1), 1.0, atol=1e-12)
    np.testing.assert_allclose(m.weights.sum(1), 1.0, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(m.covars) > 0)
    h = np.array(report.history)
    assert np.all(np.diff(h) > -1e-6 * np.abs(h[1:]))  # EM never decreases the log-likelihood
    assert report.final_loglik >= h[-1] - 1e-6 * abs(h[-1])
    assert report.final_loglik == pytest.approx(sum(ref_forward(X, *params(m))[-1] for X in seqs), rel=1e-10)
    assert report.n_sequences == len(seqs) and report.n_frames == sum(len(X) for X in seqs)


@pytest.mark.parametrize(("action", "n_states", "n_mix"), [("grasp", 6, 3), ("tap", 4, 1), ("touch", 3, 2)])
def test_vectorised_em_with_hmmlearns_covariance_step_equals_hmmlearns_fit(corpus, action, n_states, n_mix):
    """glu's reference E-step with hmmlearn's covariance step is hmmlearn's GMMHMM update: the same history
    and parameters after 12 iterations."""
    from glu.hmm import em as bw
    from glu.hmm.initialisation import init_left_to_right

    seqs = [s.xyz for s in corpus if s.action == action]
    init = init_left_to_right(seqs, n_states, n_mix, 1e-3, 0)
    start = bw.GMMHMMParams(init.startprob, init.transmat, init.weights, init.means, init.covars)
    ref = train_hmmlearn(seqs, start, 12, 1e-9 * sum(len(X) for X in seqs), 1e-3)
    ours = fit_hmmlearn_update(seqs, start, 12, 1e-300, 1e-3)
    np.testing.assert_allclose(ours.history, ref.history, rtol=1e-10)
    for name, got, want in zip(bw.GMMHMMParams._fields, ours.params, ref.params, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-7, atol=1e-9, err_msg=name)


def test_one_map_em_step_equals_the_textbook_update(corpus):
    """One vectorised step against an M-step written out here from scipy's densities and a plain loop."""
    from scipy.special import logsumexp
    from scipy.stats import multivariate_normal

    from glu.hmm import em as bw
    from glu.hmm.initialisation import init_left_to_right

    seqs = [s.xyz for s in corpus if s.action == "touch"][:3]
    init = init_left_to_right(seqs, 3, 2, 1e-3, 0)
    start = bw.GMMHMMParams(init.startprob, init.transmat, init.weights, init.means, init.covars)
    Q, M, D, r = 3, 2, 3, 1e-3
    with np.errstate(divide="ignore"):
        log_a, log_pi = np.log(init.transmat), np.log(init.startprob)
    N_qm, S1, S2 = np.zeros((Q, M)), np.zeros((Q, M, D)), np.zeros((Q, M, D, D))
    xi_sum, start_sum = np.zeros((Q, Q)), np.zeros(Q)
    resp = []
    for X in seqs:
        lc = np.array(
            [
                [
                    np.log(init.weights[q, m])
                    + multivariate_normal(init.means[q, m], init.covars[q, m]).logpdf(X)
                    for m in range(M)
                ]
                for q in range(Q)
            ]
        ).transpose(2, 0, 1)  # (T, Q, M)
        lb = logsumexp(lc, axis=2)
        T = len(X)
        fa, ba = np.zeros((T, Q)), np.zeros((T, Q))
        fa[0] = log_pi + lb[0]
        for t in range(1, T):
            fa[t] = logsumexp(fa[t - 1][:, None] + log_a, axis=0) + lb[t]
        for t in range(T - 2, -1, -1):
            ba[t] = logsumexp(log_a + lb[t + 1] + ba[t + 1], axis=1)
        ll = logsumexp(fa[-1])
        g = np.exp(fa + ba - ll)
        start_sum += g[0]
        for t in range(T - 1):
            xi_sum += np.exp(fa[t][:, None] + log_a + (lb[t + 1] + ba[t + 1])[None, :] - ll)
        rr = g[:, :, None] * np.exp(lc - lb[:, :, None])
        resp.append((X, rr))
        N_qm += rr.sum(axis=0)
        S1 += np.einsum("tqm,td->qmd", rr, X)
    means = S1 / N_qm[..., None]
    for X, rr in resp:
        for q in range(Q):
            for m in range(M):
                d = X - means[q, m]
                S2[q, m] += (rr[:, q, m, None] * d).T @ d
    covars = (S2 + r * np.eye(D)) / (N_qm + 1)[..., None, None]
    transmat = xi_sum / xi_sum.sum(axis=1, keepdims=True)
    weights = N_qm / N_qm.sum(axis=1, keepdims=True)
    ours = bw.fit(seqs, start, 1, 1e-300, r, "map").params
    np.testing.assert_allclose(ours.startprob, start_sum / start_sum.sum(), atol=1e-12)
    np.testing.assert_allclose(ours.transmat, transmat, atol=1e-10)
    np.testing.assert_allclose(ours.weights, weights, atol=1e-10)
    np.testing.assert_allclose(ours.means, means, rtol=1e-9)
    np.testing.assert_allclose(ours.covars, covars, rtol=1e-8)


def test_glu_em_stops_like_hmmlearn_and_gains_at_least_as_much(corpus):
    seqs = [s.xyz for s in corpus if s.action == "tap"]
    weak = TrainingConfig(n_states=4, n_mix=2, n_iter=200, tol=1e-3, covar_reg=1e-3)  # nearly the likelihood
    from glu.hmm.em import GMMHMMParams
    from glu.hmm.initialisation import init_left_to_right

    _, r_ours = train(seqs, weak, warn=False)
    init = init_left_to_right(seqs, 4, 2, 1e-3, 0)
    start = GMMHMMParams(init.startprob, init.transmat, init.weights, init.means, init.covars)
    n_frames = sum(len(X) for X in seqs)
    ref = train_hmmlearn(seqs, start, 200, 1e-3 * n_frames, 1e-3)
    assert r_ours.converged and len(ref.history) < 200 and ref.history[-1] - ref.history[-2] < 1e-3 * n_frames
    final_ref = sum(GestureHMM(*ref.params).loglik(X) for X in seqs)
    assert r_ours.final_loglik >= final_ref - 1e-6 * abs(final_ref)


def test_non_convergence_is_reported(corpus):
    seqs = [s.xyz for s in corpus if s.action == "tap"]
    with pytest.warns(HMMConvergenceWarning, match="NOT converged after 2 of 2"):
        _, report = train(seqs, TrainingConfig(n_states=4, n_mix=1, n_iter=2, tol=1e-9), name="tap")
    assert not report.converged and report.n_iter == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error", HMMConvergenceWarning)
        _, report = train(seqs, TrainingConfig(n_states=4, n_mix=1, n_iter=300, tol=1e-3), name="tap")
    assert report.converged and report.n_iter < 300
    assert abs(report.history[-1] - report.history[-2]) < 1e-3 * report.n_frames


def test_trained_recogniser_recognises_held_out_synthetic_gestures(corpus):
    from glu.gestures.corpus import synthetic_corpus

    train = {a: [s.xyz for s in corpus if s.action == a] for a in ("grasp", "tap", "touch")}
    rec = train_recognizer(train, TrainingConfig(n_states=4, n_mix=1, n_iter=30), warn=False)
    test = synthetic_corpus(12, seed=99, actions=("grasp", "tap", "touch"))
    acc = np.mean([rec.classify(s.xyz) == s.action for s in test])
    assert acc >= 0.75  # chance is 1/3


def test_training_input_errors():
    with pytest.raises(DataError, match="no sequences"):
        train([])
    with pytest.raises(DataError, match="too few"):
        train([np.zeros((3, 3))], TrainingConfig(n_states=6, n_mix=3))
    with pytest.raises(DataError, match="sequence 2"):
        train([np.zeros((30, 3)), np.zeros((30, 2))])
    with pytest.raises(ModelError, match="n_states=0"):
        TrainingConfig(n_states=0)
    with pytest.raises(ModelError, match="unknown training recipe 'htk'"):
        TrainingConfig(recipe="htk")


def test_a_model_that_cannot_be_trained_is_named_alone_or_in_a_batch():
    """With covar_reg 0, a feature that never varies makes a covariance singular. Alone or trained in one
    batch with a model that trains, the error is one ModelError naming that model (a batch's retry used to
    raise TypeError, and the initial mixtures a bare ValueError)."""
    rng = np.random.default_rng(0)
    good = [rng.normal(size=(30, 3)) for _ in range(4)]
    flat = [np.c_[rng.normal(size=(30, 2)), np.zeros(30)] for _ in range(3)]  # the third feature is 0
    config = TrainingConfig(n_states=2, n_mix=1, n_iter=5, covar_reg=0.0)
    start = GestureHMM(
        [1.0, 0.0],
        left_to_right_transmat(2, 0.9),
        [[1.0], [1.0]],
        [[[0.0] * 3], [[1.0] * 3]],
        np.tile(np.eye(3), (2, 1, 1, 1)),
    )
    weights = {"a": [1.0] * 4, "b": [1.0] * 3}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert list(train({"a": good}, config, weights={"a": weights["a"]})) == ["a"]  # a trains
        for jobs in ({"a": good, "b": flat}, {"b": flat, "a": good}, {"b": flat}):
            with pytest.raises(ModelError, match=r"^EM failed for b: "):
                train(jobs, config, weights={k: weights[k] for k in jobs}, start={"b": start})
            with pytest.raises(ModelError, match=r"the initial model of b failed: .*covar_reg \(now 0\.0\)"):
                train(jobs, config)
        assert list(train({"a": good, "b": flat}, TrainingConfig(n_states=2, n_mix=1, n_iter=5))) == [
            "a",
            "b",
        ]


def test_model_validation():
    rng = np.random.default_rng(9)
    m = random_model(rng)
    with pytest.raises(ModelError, match="transmat must have shape"):
        GestureHMM(m.startprob, m.transmat[:2], m.weights, m.means, m.covars)
    with pytest.raises(ModelError, match="startprob must be non-negative and sum to one"):
        GestureHMM(m.startprob * 2, m.transmat, m.weights, m.means, m.covars)
    with pytest.raises(ModelError, match="non-finite"):
        GestureHMM(m.startprob, m.transmat, m.weights, m.means * np.nan, m.covars)
    np.testing.assert_allclose(
        left_to_right_transmat(3, 0.8), [[0.8, 0.2, 0], [0, 0.8, 0.2], [0, 0, 1]], atol=1e-15
    )


# --- the original 2013 models ------------------------------------------------------------------------


def mat_params(mat, k):
    """The parameters of hmm{k} straight from the .mat arrays, in our (Q, M, …) layout."""
    prior = mat[f"hmm{k}_prior"].astype(float).ravel()
    Q = len(prior)
    w = mat[f"hmm{k}_mixmat"].astype(float).reshape(Q, -1)
    M = w.shape[1]
    mu = mat[f"hmm{k}_mu"].reshape(3, Q, M).transpose(1, 2, 0)
    sig = mat[f"hmm{k}_Sigma"].reshape(3, 3, Q, M).transpose(2, 3, 0, 1)
    return prior, mat[f"hmm{k}_trans"].astype(float), w, mu, sig


def write_original_mat(models: dict[int, GestureHMM], path) -> None:
    """Save models in the layout of the originals' .mat files (docs/method.md §4.4), independently of glu's
    reader."""
    from scipy.io import savemat

    out = {}
    for k, m in models.items():
        out[f"hmm{k}_prior"] = m.startprob.reshape(-1, 1)
        out[f"hmm{k}_trans"] = m.transmat
        out[f"hmm{k}_mixmat"] = m.weights
        out[f"hmm{k}_mu"] = m.means.transpose(2, 0, 1)  # D × Q × M
        out[f"hmm{k}_Sigma"] = m.covars.transpose(2, 3, 0, 1)  # D × D × Q × M
    savemat(path, out)


@pytest.mark.parametrize("n_mix", [3, 1])
def test_original_layout_files_are_read_as_written(tmp_path, n_mix):
    from hmmlearn.hmm import GMMHMM

    rng = np.random.default_rng(10 + n_mix)
    models = {k: random_model(rng, Q=6, M=n_mix, D=3) for k in (0, 1, 3, 4)}
    path = tmp_path / f"HMM_M{n_mix}_Q6_mixsplit.mat"
    write_original_mat(models, path)
    rec = load_original_models(path, include_garbage=True)
    assert rec.actions == ("grasp", "tap", "touch", "garbage")
    mat = loadmat(path)
    X = rng.normal(size=(40, 3))
    for action, k in (("grasp", 3), ("tap", 1), ("touch", 4), ("garbage", 0)):
        for ours, ref in zip(params(rec.models[action]), params(models[k]), strict=True):
            np.testing.assert_array_equal(ours, ref)
        pi, A, w, mu, sig = mat_params(mat, k)
        ll = rec.models[action].loglik_curve(X)
        np.testing.assert_allclose(ll, ref_forward(X, pi, A, w, mu, sig), rtol=1e-10)
        h = GMMHMM(n_components=6, n_mix=n_mix, covariance_type="full", init_params="")
        h.n_features = 3
        h.startprob_, h.transmat_, h.weights_, h.means_, h.covars_ = pi, A, w, mu, sig
        assert ll[-1] == pytest.approx(h.score(X), abs=1e-8)
    ll, p = rec.stream().extend(X)
    np.testing.assert_allclose(ll[:, 1], ref_forward(X, *mat_params(mat, 1)), rtol=1e-10)
    np.testing.assert_allclose(p.sum(1), 1.0)


def test_original_model_file_errors(tmp_path):
    with pytest.raises(ModelError, match="no such file"):
        load_original_models(tmp_path / "none.mat")
    (tmp_path / "bad.mat").write_bytes(b"not a mat file at all")
    with pytest.raises(ModelError, match="not a readable MATLAB file"):
        load_original_models(tmp_path / "bad.mat")
    from scipy.io import savemat

    savemat(tmp_path / "partial.mat", {"hmm1_prior": np.ones(2)})
    with pytest.raises(ModelError, match="missing hmm3_prior"):
        load_original_models(tmp_path / "partial.mat")


def test_forward_log_domain_fallback_closed_form():
    # frame 1 fits only the unreachable state 1: every scaled emission of state 0 underflows to zero
    lb = np.array([[-2000.0, 0.0], [-1.0, -3000.0]])
    A = np.array([[0.5, 0.5], [0.0, 1.0]])
    curve = forward_curve(lb, np.array([1.0, 0.0]), A)
    assert curve[0] == pytest.approx(-2000.0, abs=1e-9)
    expected = np.logaddexp(-2000.0 + np.log(0.5) - 1.0, -2000.0 + np.log(0.5) - 3000.0)
    assert curve[1] == pytest.approx(expected, abs=1e-9)
    # an impossible frame (no reachable state can emit it) gives -inf from there on
    lb_impossible = np.array([[0.0, 0.0], [-np.inf, 0.0], [0.0, 0.0]])
    stay = np.eye(2)
    assert np.isneginf(forward_curve(lb_impossible, np.array([1.0, 0.0]), stay)[1:]).all()


def test_batched_forward_backward_equals_brute_force_over_state_paths():
    """γ, Σξ and log L of a padded batch, scaled and log-domain, against enumerating every state path."""
    import itertools

    from glu.hmm.inference import forward_backward, forward_backward_log

    rng = np.random.default_rng(4)
    Q, lengths = 3, np.array([4, 2, 5])
    A = np.array([[0.6, 0.4, 0.0], [0.0, 0.7, 0.3], [0.0, 0.0, 1.0]])
    pi = np.array([0.8, 0.2, 0.0])
    log_b = rng.normal(size=(3, 5, Q)) * 2
    log_b[1, 2:] = 123.0  # padding: must be ignored
    gamma_ref = np.zeros((3, 5, Q))
    xi_ref = np.zeros((Q, Q))
    ll_ref = np.zeros(3)
    for s, T in enumerate(lengths):
        total, g, xi = 0.0, np.zeros((T, Q)), np.zeros((Q, Q))
        for path in itertools.product(range(Q), repeat=int(T)):
            p = pi[path[0]] * np.exp(log_b[s, 0, path[0]])
            for t in range(1, T):
                p *= A[path[t - 1], path[t]] * np.exp(log_b[s, t, path[t]])
            total += p
            for t in range(T):
                g[t, path[t]] += p
            for t in range(T - 1):
                xi[path[t], path[t + 1]] += p
        gamma_ref[s, :T] = g / total
        xi_ref += xi / total
        ll_ref[s] = np.log(total)
    for fb in (forward_backward, forward_backward_log):
        gamma, xi_sum, ll = fb(log_b, lengths, pi, A)
        np.testing.assert_allclose(ll, ll_ref, rtol=1e-12)
        np.testing.assert_allclose(gamma, gamma_ref, atol=1e-12)
        np.testing.assert_allclose(xi_sum, xi_ref, atol=1e-12)


def test_batched_forward_backward_falls_back_to_the_log_domain_on_underflow():
    from glu.hmm.inference import forward_backward, forward_backward_log

    A = np.array([[0.9, 0.1, 0.0], [0.0, 0.9, 0.1], [0.0, 0.0, 1.0]])
    pi = np.array([1.0, 0.0, 0.0])
    # frame 2: only states 0 and 1 are reachable, and their emissions are e^-2000 times the best one's
    log_b = np.array([[[0.0, -1.0, -1.0], [-2000.0, -2000.0, 0.0], [-1.0, -3.0, -2.0]]])
    lengths = np.array([3])
    scaled = np.exp(log_b[0, 1] - log_b[0, 1].max())
    assert (
        pi @ A * scaled
    ).sum() == 0.0  # the scaled recursion underflows here: the log domain must take over
    g, xi, ll = forward_backward(log_b, lengths, pi, A)
    g_ref, xi_ref, ll_ref = forward_backward_log(log_b, lengths, pi, A)
    assert np.isfinite(ll).all()
    np.testing.assert_allclose(ll, ll_ref, rtol=1e-12)
    np.testing.assert_allclose(g, g_ref, atol=1e-12)
    np.testing.assert_allclose(xi, xi_ref, atol=1e-12)


def test_sampling_draws_what_hmmlearn_draws(bank):
    """GestureHMM.sample makes hmmlearn's draws in hmmlearn's order: the same sequence for the same seed."""
    for m in bank.models.values():
        for seed in (0, 7):
            np.testing.assert_array_equal(m.sample(25, seed), to_hmmlearn(m).sample(25, random_state=seed)[0])


# --- bad models, bad training requests, and the rare paths of training ----------------------------------


def test_a_mixture_component_of_weight_zero_is_allowed_and_ignored():
    """A weight of 0 leaves its component out of the density (the model documents it: its log_norm is −∞);
    such a model was refused as "too close to singular" before. Scores equal the scipy reference, which
    skips the component."""
    rng = np.random.default_rng(11)
    m = random_model(rng, Q=3, M=3, D=2)
    w = np.array([[0.5, 0.5, 0.0], [0.3, 0.0, 0.7], [1.0, 0.0, 0.0]])
    zero = GestureHMM(m.startprob, m.transmat, w, m.means, m.covars)
    assert np.isneginf(zero.log_norm[w == 0]).all()
    X = rng.normal(size=(25, 2))
    np.testing.assert_allclose(zero.loglik_curve(X), ref_forward(X, *params(zero)), rtol=1e-10)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"means": np.zeros((3, 2))}, r"means must have shape \(Q, M, D\), got \(3, 2\)"),
        (
            {"covars": np.array([[[[1.0, 0.5], [0.0, 1.0]]]] * 3).reshape(3, 1, 2, 2)},
            "covariances must be symmetric",
        ),
    ],
)
def test_malformed_model_parameters(change, message):
    rng = np.random.default_rng(12)
    m = random_model(rng, Q=3, M=1, D=2)
    p = {
        "startprob": m.startprob,
        "transmat": m.transmat,
        "weights": m.weights,
        "means": m.means,
        "covars": m.covars,
    }
    with pytest.raises(ModelError, match=message):
        GestureHMM(**{**p, **change}, name="mine")


def test_a_sequence_must_be_numbers():
    from glu.hmm.model import as_sequence

    with pytest.raises(DataError, match="gesture: not an array of numbers"):
        as_sequence([["a", "b", "c"]], 3, "gesture")
    with pytest.raises(DataError, match="gesture: not an array of numbers"):
        as_sequence([[1.0, 2.0], [3.0]], 2, "gesture")


def test_training_settings_and_requests_that_are_refused():
    seqs = [np.random.default_rng(k).normal(size=(20, 2)) for k in range(3)]
    for bad in ({"n_iter": 0}, {"tol": 0.0}, {"n_iter": 2.5}):
        with pytest.raises(ModelError, match="must be ≥ 1 and tol=.* > 0"):
            TrainingConfig(**bad)
    with pytest.raises(ModelError, match="one model takes one list of weights, one seed and one start"):
        train(seqs, weights={"a": [1.0] * 3})
    with pytest.raises(ModelError, match="one model takes one list of weights"):
        train(seqs, seed={"a": 1})
    with pytest.raises(ModelError, match="give a mapping of weights with the same keys"):
        train({"a": seqs, "b": seqs}, weights={"a": [1.0] * 3})
    with pytest.raises(ModelError, match="give a mapping of weights with the same keys"):
        train({"a": seqs}, weights=[1.0] * 3)
    with pytest.raises(ModelError, match="no seed for b"):
        train({"a": seqs, "b": seqs}, seed={"a": 1})


@pytest.mark.slow
def test_models_under_other_keys_are_named_by_str():
    from glu.hmm.training import model_name

    assert [model_name(k) for k in ("tap", (0, "tap"), 7, (), None)] == ["tap", "tap", "7", "()", "None"]
    seqs = [np.random.default_rng(k).normal(size=(20, 2)) for k in range(3)]
    cfg = TrainingConfig(n_states=2, n_mix=1, n_iter=3)
    assert train({7: seqs}, cfg, warn=False)[7].model.name == "7"


def test_weighted_training_starts_from_every_weighted_sequence_when_the_heavy_ones_are_too_short():
    """The sequences of at least half the largest weight give the initial model, unless they hold fewer than
    Q·M frames (here 4 < 6): then every sequence of positive weight does."""
    rng = np.random.default_rng(13)
    seqs = [rng.normal(size=(4, 2)), rng.normal(size=(30, 2)), rng.normal(size=(30, 2))]
    w = [1.0, 0.2, 0.0]
    cfg = TrainingConfig(n_states=3, n_mix=2, n_iter=5)
    got = train(seqs, cfg, weights=w, seed=3, warn=False).model
    start = init_left_to_right(seqs[:2], 3, 2, cfg.covar_reg, 3)
    ref = train(seqs, cfg, weights=w, start=start, warn=False).model
    for a, b in zip(params(got), params(ref), strict=True):
        np.testing.assert_array_equal(a, b)


def _collapsing(n_random=11, seed=0):
    """Sequences whose last frames are one point: EM can give a state a covariance of 0 without a floor."""
    rng = np.random.default_rng(seed)
    return [np.vstack([rng.normal(size=(n_random, 1)), np.ones((20 - n_random, 1))]) for _ in range(3)]


def test_em_that_collapses_a_state_names_the_model_and_the_remedy():
    """Without covar_reg, a state that takes only the repeated point gets a zero covariance: at the last
    M-step the fitted model is invalid, earlier the next E-step fails (at which iteration it collapses is left
    to the floating point). Either way one ModelError naming the model."""
    said = {}
    for n_iter in range(1, 10):
        try:
            train(
                {"bad": _collapsing()},
                TrainingConfig(n_states=2, n_mix=1, covar_reg=0.0, n_iter=n_iter),
                warn=False,
            )
        except ModelError as e:
            said[str(e).split(" for bad")[0]] = str(e)
            assert "for bad" in str(e) and "\n" not in str(e)
    assert set(said) == {"EM diverged", "EM failed"}
    assert said["EM diverged"].startswith(
        "EM diverged for bad (HMM 'bad': a covariance matrix is not positive definite); "
        "try a larger covar_reg"
    )


def test_original_model_files_with_bad_contents(tmp_path, monkeypatch):
    from glu.hmm.original import load_original_hmms, original_hmm

    rng = np.random.default_rng(14)
    m = random_model(rng, Q=2, M=2, D=3)
    mat = {
        "hmm1_prior": m.startprob[:, None],
        "hmm1_trans": m.transmat,
        "hmm1_mixmat": m.weights,
        "hmm1_mu": np.zeros((3, 2, 3)),  # M = 3 means for M = 2 weights
        "hmm1_Sigma": np.zeros((3, 3, 2, 2)),
    }
    with pytest.raises(
        ModelError, match=r"model hmm1: mu \(3, 2, 3\) / Sigma \(3, 3, 2, 2\) do not fit Q=2, M=2"
    ):
        original_hmm(mat, 1)
    path = tmp_path / "HMM_M3_Q6_mixsplit.mat"
    write_original_mat({k: random_model(rng, Q=6, M=3, D=3) for k in (0, 1, 3, 4)}, path)
    with pytest.raises(ModelError, match="no original model for 'push'; allowed: grasp, tap, touch, garbage"):
        load_original_hmms(path, actions=("tap", "push"))

    def unreadable(path, **options):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr("glu.matfile.read_mat", unreadable)
    with pytest.raises(
        ModelError, match=r"HMM_M3_Q6_mixsplit.mat: not a readable MATLAB file \(\[Errno 5\] Input/output"
    ):
        load_original_hmms(path)


def test_forward_of_no_frames_is_empty_and_kmeans_needs_enough_points():
    from glu.hmm.initialisation import kmeans_labels

    assert forward_curve(np.zeros((0, 3)), np.ones(3) / 3, np.eye(3)).shape == (0,)
    for k in (0, 5):
        with pytest.raises(ModelError, match=f"k-means needs between 1 and n_samples=4 clusters, got {k}"):
            kmeans_labels(np.zeros((4, 2)), k, 0)


def test_an_unknown_covariance_update_is_refused():
    from glu.hmm.em import GMMHMMParams, fit

    m = random_model(np.random.default_rng(15), Q=2, M=1, D=2)
    init = GMMHMMParams(*params(m))
    with pytest.raises(ModelError, match="unknown covariance update 'diag'; allowed: "):
        fit([np.zeros((5, 2))], init, 3, 1e-4, covariance="diag")
