"""The originals' training recipe (mixsplit): closed forms, EM properties, hmmlearn, and the recipe
comparison."""

from __future__ import annotations

import json

import numpy as np
import pytest

from glu.cli import main
from glu.errors import ModelError
from glu.gestures.corpus import synthetic_corpus
from glu.gestures.recognizer import Recognizer, train_recognizer
from glu.hmm import TrainingConfig
from glu.hmm import mixsplit as ms
from glu.hmm.inference import left_to_right_transmat
from glu.hmm.model import GestureHMM

MIXSPLIT = TrainingConfig(recipe="mixsplit")


@pytest.fixture(scope="module")
def taps():
    """Synthetic tap gestures (features of shape (T_i, 3))."""
    return [s.xyz for s in synthetic_corpus(6, seed=3, actions=("tap",))]


def test_flat_start_is_the_global_gaussian_with_half_transitions(taps):
    hmm = ms.flat_start(taps, 4, "tap")
    X = np.vstack(taps)
    mean = X.sum(axis=0) / len(X)
    cov = (X - mean).T @ (X - mean) / len(X)  # maximum likelihood: divided by the number of frames
    assert hmm.n_states == 4 and hmm.n_mix == 1 and hmm.name == "tap"
    np.testing.assert_allclose(hmm.means[:, 0], np.tile(mean, (4, 1)), rtol=1e-12)
    np.testing.assert_allclose(hmm.covars[:, 0], np.tile(cov, (4, 1, 1)), rtol=1e-12)
    expected = np.array([[0.5, 0.5, 0, 0], [0, 0.5, 0.5, 0], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])
    np.testing.assert_array_equal(hmm.transmat, expected)
    np.testing.assert_array_equal(hmm.startprob, [1, 0, 0, 0])


def test_split_heaviest_halves_the_heaviest_component_of_each_state():
    rng = np.random.default_rng(0)
    covars = np.array([np.diag(rng.uniform(0.5, 2, 2)) + 0.1 for _ in range(4)]).reshape(2, 2, 2, 2)
    means = rng.normal(size=(2, 2, 2))
    hmm = GestureHMM([1, 0], left_to_right_transmat(2, 0.7), [[0.3, 0.7], [0.6, 0.4]], means, covars)
    out = ms.split_heaviest(hmm)
    assert out.n_mix == 3
    # state 0: component 1 (weight 0.7) splits; state 1: component 0 (weight 0.6)
    for q, j, other in ((0, 1, 0), (1, 0, 1)):
        d = 0.2 * np.sqrt(np.diag(covars[q, j]))
        np.testing.assert_allclose(out.means[q, j], means[q, j] + d)
        np.testing.assert_allclose(out.means[q, 2], means[q, j] - d)
        np.testing.assert_array_equal(out.covars[q, 2], covars[q, j])
        np.testing.assert_array_equal(out.covars[q, j], covars[q, j])
        assert out.weights[q, j] == out.weights[q, 2] == hmm.weights[q, j] / 2
        np.testing.assert_array_equal(out.means[q, other], means[q, other])  # the other component is kept
        assert out.weights[q, other] == hmm.weights[q, other]
    np.testing.assert_array_equal(out.transmat, hmm.transmat)


def test_log_likelihood_never_decreases_within_a_stage_and_components_grow(taps):
    hmm, report, stages = ms.train_one(
        taps,
        MIXSPLIT.replace(n_states=4, n_mix=3, covar_floor=0.0, tol=1e-5, n_iter=40),
        name="tap",
        warn=False,
    )
    assert [len(h) >= 2 for h in stages] == [True] * 3  # stages M = 1, 2, 3
    for history in stages:  # plain maximum likelihood: EM cannot lower the likelihood
        h = np.array(history)
        assert np.all(np.diff(h) >= -1e-9 * np.abs(h[1:]).max()), np.diff(h).min()
    assert stages[1][0] > stages[0][0] and stages[2][-1] >= stages[1][-1] - 1e-9 * abs(stages[1][-1])
    assert hmm.n_mix == 3 and report.n_iter == sum(len(h) for h in stages)
    assert report.final_loglik == pytest.approx(sum(hmm.loglik(X) for X in taps), rel=1e-9)


def test_left_to_right_zeros_survive_every_stage(taps):
    hmm, _, _ = ms.train_one(taps, MIXSPLIT.replace(n_states=5, n_mix=2), name="tap")
    A = hmm.transmat
    assert np.all(np.tril(A, -1) == 0) and np.all(np.triu(A, 2) == 0)  # only stay or next, as the flat start
    np.testing.assert_array_equal(hmm.startprob, [1, 0, 0, 0, 0])
    assert hmm.is_left_to_right


def test_the_covariance_floor_is_the_originals(taps):
    hmm, _, _ = ms.train_one(taps, MIXSPLIT.replace(n_states=4, n_mix=2), name="tap")
    eig = np.linalg.eigvalsh(hmm.covars.reshape(-1, 3, 3))
    assert eig.min() >= MIXSPLIT.covar_floor * (1 - 1e-9)  # every covariance is ML + 0.01·I


def test_a_stage_is_hmmlearns_baum_welch(taps):
    """M = 1 from the flat start: the same iterations as hmmlearn's GaussianHMM (another code path)."""
    from hmmlearn.hmm import GaussianHMM

    start = ms.flat_start(taps, 4)
    ours, history = ms.baum_welch(start, taps, n_iter=8, tol=1e-300, covar_floor=0.0)
    ref = GaussianHMM(
        4,
        covariance_type="full",
        n_iter=8,
        tol=1e-300,
        params="stmc",
        init_params="",
        covars_prior=0.0,
        implementation="log",
    )
    ref.startprob_, ref.transmat_ = start.startprob.copy(), start.transmat.copy()
    ref.means_, ref.covars_ = start.means[:, 0].copy(), start.covars[:, 0].copy()
    ref.fit(np.vstack(taps), [len(X) for X in taps])
    assert len(history) == len(ref.monitor_.history) == 8
    np.testing.assert_allclose(history, ref.monitor_.history, rtol=1e-9)
    np.testing.assert_allclose(ours.transmat, ref.transmat_, atol=1e-9)
    np.testing.assert_allclose(ours.means[:, 0], ref.means_, atol=1e-9)
    np.testing.assert_allclose(ours.covars[:, 0], ref.covars_, atol=1e-9)


def _posteriors_by_hand(hmm, X):
    """Component posteriors r[t, q, m] of one sequence, by a log-domain forward-backward written here
    (scipy)."""
    from scipy.special import logsumexp
    from scipy.stats import multivariate_normal

    Q, M = hmm.weights.shape
    lc = np.array(
        [
            [
                np.log(hmm.weights[q, m]) + multivariate_normal(hmm.means[q, m], hmm.covars[q, m]).logpdf(X)
                for m in range(M)
            ]
            for q in range(Q)
        ]
    ).transpose(2, 0, 1)  # (T, Q, M)
    lb = logsumexp(lc, axis=2)  # (T, Q)
    with np.errstate(divide="ignore"):
        lA, lpi = np.log(hmm.transmat), np.log(hmm.startprob)
    T = len(X)
    la, lbeta = np.empty((T, Q)), np.zeros((T, Q))
    la[0] = lpi + lb[0]
    for t in range(1, T):
        la[t] = logsumexp(la[t - 1][:, None] + lA, axis=0) + lb[t]
    for t in range(T - 2, -1, -1):
        lbeta[t] = logsumexp(lA + (lb[t + 1] + lbeta[t + 1])[None, :], axis=1)
    lgamma = la + lbeta - logsumexp(la[-1])
    return np.exp(lgamma[:, :, None] + lc - lb[:, :, None])


def test_one_em_step_with_mixtures_equals_the_textbook_m_step(taps):
    """M = 2: weights, means and covariances after one iteration, against the M-step written out by hand."""
    start = ms.split_heaviest(ms.flat_start(taps, 3))
    ours, _ = ms.baum_welch(start, taps, n_iter=1, tol=1e-300, covar_floor=0.01)
    r = np.concatenate([_posteriors_by_hand(start, X) for X in taps])  # (T, Q, M)
    X = np.vstack(taps)
    N = r.sum(axis=0)
    mu = np.einsum("tqm,td->qmd", r, X) / N[..., None]
    diff = X[:, None, None, :] - mu[None]
    cov = np.einsum("tqm,tqmd,tqme->qmde", r, diff, diff) / N[..., None, None] + 0.01 * np.eye(3)
    np.testing.assert_allclose(ours.weights, N / N.sum(axis=1, keepdims=True), atol=1e-9)
    np.testing.assert_allclose(ours.means, mu, atol=1e-9)
    np.testing.assert_allclose(ours.covars, cov, atol=1e-9)


def test_bad_settings(taps):
    with pytest.raises(ModelError, match="covar_floor"):
        MIXSPLIT.replace(covar_floor=-1)
    with pytest.raises(ModelError, match="unknown training recipe 'htk'"):
        TrainingConfig(recipe="htk")


def _collapsing():
    """Sequences whose last frames are one point: Baum–Welch without a floor can give a state a covariance
    of 0."""
    rng = np.random.default_rng(0)
    rng.normal(size=60)
    return [np.vstack([rng.normal(size=(8, 1)), np.ones((12, 1))]) for _ in range(3)]


def test_a_collapsing_stage_is_one_error_naming_the_model():
    """Without covar_floor, the repeated point's state collapses: at the last M-step the fitted model is
    invalid, after it the next E-step fails (at which iteration is left to the floating point); trained with
    a sound model, the error still names the one that failed (each is trained again alone)."""
    from glu.hmm import train

    def error(data, n_iter):
        config = TrainingConfig(recipe="mixsplit", n_states=2, n_mix=1, n_iter=n_iter, covar_floor=0.0)
        try:
            train(data, config, warn=False)
        except ModelError as e:
            assert "\n" not in str(e)
            return str(e)
        return None

    said = {error({"bad": _collapsing()}, n_iter) for n_iter in range(1, 13)} - {None}
    diverged = "Baum–Welch diverged for bad at M = 1 (HMM 'bad': a covariance matrix is not positive definite"
    assert "Baum–Welch failed for bad at M = 1: Matrix is not positive definite" in said, said
    assert any(m.startswith(diverged + "); try covar_floor > 0") for m in said), said
    good = [np.random.default_rng(k).normal(size=(20, 1)) for k in range(3)]
    assert error({"good": good, "bad": _collapsing()}, 20).startswith("Baum–Welch failed for bad at M = 1")


def test_recognizer_and_command_line(tmp_path, capsys, taps):
    rec = train_recognizer(
        {"tap": taps, "grasp": taps[:3]},
        TrainingConfig(n_states=3, n_mix=2, recipe="mixsplit", n_iter=20),
        warn=False,
    )
    assert rec.config.recipe == "mixsplit" and rec.models["tap"].n_mix == 2
    out = tmp_path / "ms.json"
    argv = [
        "hmm",
        "train",
        "--synthetic",
        "4",
        "--recipe",
        "mixsplit",
        "--states",
        "3",
        "--mix",
        "2",
        "--iter",
        "15",
        "-o",
        str(out),
    ]
    assert main(argv) == 0
    assert "wrote" in capsys.readouterr().out
    saved = Recognizer.load(out)
    assert saved.config.recipe == "mixsplit" and json.loads(out.read_text())["config"]["n_mix"] == 2
    with pytest.raises(SystemExit) as e:
        main(["hmm", "train", "--synthetic", "4", "--recipe", "htk", "-o", str(out)])
    assert e.value.code == 2 and "invalid choice: 'htk'" in capsys.readouterr().err


@pytest.mark.parametrize("recipe", ["glu", "mixsplit"])
def test_fast_leave_one_segment_out_equals_the_general_one(recipe):
    from glu.studies.replication.gestures import leave_one_out
    from glu.studies.replication.recipes import leave_one_segment_out

    corpus = synthetic_corpus(3, seed=1)
    settings = {"config": TrainingConfig(n_states=3, n_mix=2, n_iter=8, tol=1e-3, recipe=recipe)}
    fast, everything = leave_one_segment_out(corpus, seed=2, **settings)
    slow = leave_one_out(corpus, by="segment", seed=2, **settings)
    assert list(fast["predicted"]) == list(slow["predicted"])
    assert list(fast["correct"]) == list(slow["correct"])
    assert set(everything.actions) == {"grasp", "tap", "touch"}


def test_recipe_comparison_on_synthetic_segments():
    from glu.studies.replication.recipes import recipe_comparison, recipe_spread

    corpus = synthetic_corpus(3, seed=1)
    test = synthetic_corpus(1, seed=9)
    config = TrainingConfig(n_states=3, n_mix=2, n_iter=8)
    df = recipe_comparison(corpus, test, seeds=(0, 1), tols=(1e-3,), config=config)
    assert list(df["recipe"]) == ["glu", "glu", "mixsplit"] and list(df["seed"]) == [0, 1, -1]
    assert (df["loso_testable"] == len(corpus)).all()
    assert np.allclose(df["loso_accuracy"], df["loso_correct"] / df["loso_testable"])
    assert all(len(p.split(",")) == len(test) for p in df["test_predicted"])
    spread = recipe_spread(df)
    assert list(spread["recipe"]) == ["glu", "mixsplit"] and (spread["loso_min"] <= spread["loso_max"]).all()
    assert spread["n_test"].tolist() == [len(test)] * 2
