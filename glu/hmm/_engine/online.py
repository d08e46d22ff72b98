"""The E-step of one sequence under many models at once: online learning, one episode at a time.

A robot that updates its gesture models after each episode runs one E-step per episode and model
(:func:`glu.hmm.em.expected_stats`, the readable reference, handles many sequences under one model). When
many learners watch the same episode — the labelling schemes of :mod:`glu.studies.learning.online`,
each with its own models — :func:`expected_stats_bank` runs that episode under every model together: the
emissions of every frame under every model's Gaussians are one array operation, the forward–backward
recursions run compiled (:func:`glu.hmm._engine.kernels.forward_backward_scaled`, one model after
another), and the statistics of every model come out stacked. A model under which the scaled recursion
underflows is redone in the log domain (:func:`glu.hmm.inference.forward_backward_log`), as
``expected_stats`` would.

The result equals ``expected_stats([X], model_k, [w_k])`` for each model ``k`` to rounding
(``tests/test_weighted_em.py``). :func:`glu.hmm.em.maximise` takes the stacked statistics as they are.

:func:`expected_stats_fast` and :func:`fit_weighted_fast` are the other way round — many sequences, one
model — with the same compiled recursions and the same emissions: weighted training
(:func:`glu.hmm.glu_recipe.train_weighted`) runs on them.

Emissions come from the quadratic monomials of the frames centred on their mean
(:func:`glu.hmm._engine.batch.quadratic_features`): every component's ``log w + log N(x; μ, Σ)`` is one
matrix product, and the moments of the E-step are one product of the responsibilities with the same
monomials, moved back to raw moments about the origin.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from glu.hmm._engine.batch import quadratic_features
from glu.hmm._engine.kernels import compiled, forward_backward_scaled
from glu.hmm.em import FitResult, GMMHMMParams, SufficientStats, iterate, sequence_weights
from glu.hmm.inference import TINY, _logsumexp, forward_backward_log, gaussian_factors


def expected_stats_bank(
    X: np.ndarray, params: GMMHMMParams, weights: np.ndarray | None = None
) -> SufficientStats:
    """Sufficient statistics of one sequence under each of ``K`` models, stacked.

    Parameters
    ----------
    X : array, shape (T, D) — the sequence
    params : the models' parameters stacked: startprob (K, Q), transmat (K, Q, Q), weights (K, Q, M),
        means (K, Q, M, D), covars (K, Q, M, D, D)
    weights : array, shape (K,) — the sequence's weight for each model (default all 1); a model of weight 0
        gets zero statistics

    Returns
    -------
    :class:`~glu.hmm.em.SufficientStats` with batch shape (K,); ``loglik`` is ``weight · log L(X | model)``
    (0 for weight 0). The unweighted ``log L(X | model)`` of every model is ``stats.loglik / weight``, or
    from :func:`loglik_bank`.
    """
    X = np.asarray(X, dtype=float)
    K = params.means.shape[0]
    w = np.ones(K) if weights is None else np.asarray(weights, dtype=float)
    stats, _ = _stats(X, params)
    return weigh(stats, w)


def weigh(stats: SufficientStats, weights: np.ndarray) -> SufficientStats:
    """Unweighted stacked statistics of one sequence (batch shape (K,)) times each model's weight, shape
    (K,); a weight of 0 gives exactly zero statistics, even under a model to which the sequence is
    impossible."""
    w = np.asarray(weights, dtype=float)
    fields = []
    for a in (stats.start, stats.trans, stats.counts, stats.first, stats.second, stats.loglik):
        wk = w.reshape(w.shape + (1,) * (a.ndim - 1))
        with np.errstate(invalid="ignore"):
            fields.append(np.where(wk > 0, wk * a, 0.0))
    return SufficientStats(*fields, w.copy(), w * stats.frames)


def episode_stats(X: np.ndarray, params: GMMHMMParams) -> tuple[SufficientStats, np.ndarray]:
    """The unweighted statistics of one sequence (shape (T, D)) under each of ``K`` stacked models, and
    ``log L(X | model)``, shape (K,) (see :func:`expected_stats_bank`)."""
    return _stats(np.asarray(X, dtype=float), params)


def loglik_bank(sequences: Sequence[np.ndarray], params: GMMHMMParams) -> np.ndarray:
    """``log L(X_s | model k)`` of every sequence (shapes (T_s, D)) under every one of ``K`` stacked models,
    shape (S, K): the emissions as in :func:`expected_stats_bank` (one matrix product a sequence, the
    Gaussians' coefficients computed once), the scaled forward recursion compiled, the log domain where it
    underflows. Equal to :func:`glu.hmm.loglik_many` to rounding (tested)."""
    K, Q, M, D = params.means.shape
    frames = np.concatenate([np.asarray(x, dtype=float) for x in sequences])
    centre = frames.mean(axis=0)
    chol_inv, log_norm = gaussian_factors(params.weights, params.covars)
    coef = _coefficients(params.means - centre, chol_inv, log_norm)
    out = np.empty((len(sequences), K))
    for s, X in enumerate(sequences):
        T = len(X)
        lc = (quadratic_features(np.asarray(X, dtype=float), centre) @ coef).reshape(T, K, Q, M)
        log_b = np.ascontiguousarray(np.moveaxis(lc[..., 0] if M == 1 else _logsumexp(lc, axis=-1), 0, 1))
        lengths = np.full(K, T)
        ll, ok = compiled(_forward_scaled)(
            log_b, np.ascontiguousarray(params.startprob), np.ascontiguousarray(params.transmat)
        )
        for k in np.flatnonzero(~ok):
            ll[k] = forward_backward_log(
                log_b[k : k + 1], lengths[:1], params.startprob[k], params.transmat[k]
            )[2][0]
        out[s] = ll
    return out


def _stats(X: np.ndarray, params: GMMHMMParams) -> tuple[SufficientStats, np.ndarray]:
    K, Q, M, D = params.means.shape
    T = len(X)
    centre = X.mean(axis=0)
    phi = quadratic_features(X, centre)  # (T, P): x_i x_j (i ≤ j), x_i, 1 of the centred frames
    chol_inv, log_norm = gaussian_factors(params.weights, params.covars)
    lc = (phi @ _coefficients(params.means - centre, chol_inv, log_norm)).reshape(T, K, Q, M)
    log_b = lc[..., 0] if M == 1 else _logsumexp(lc, axis=-1)  # (T, K, Q)
    log_b_k = np.ascontiguousarray(np.moveaxis(log_b, 0, 1))  # (K, T, Q)
    lengths = np.full(K, T)
    gamma, xi, loglik, ok = forward_backward_scaled(log_b_k, lengths, params.startprob, params.transmat)
    for k in np.flatnonzero(~ok):  # the scaled mass underflowed: this model in the log domain
        g, x, ll = forward_backward_log(
            log_b_k[k : k + 1], lengths[:1], params.startprob[k], params.transmat[k]
        )
        gamma[k], xi[k], loglik[k] = g[0], x, ll[0]
    with np.errstate(under="ignore"):
        post_mix = np.ones_like(lc) if M == 1 else np.exp(lc - log_b[..., None])
    pcm = np.moveaxis(gamma, 1, 0)[..., None] * post_mix  # (T, K, Q, M)
    moments = (pcm.reshape(T, -1).T @ phi).reshape(K, Q, M, -1)  # Σ_t p φ(x_t − centre)
    counts, first, second = _raw_moments(moments, centre)
    stats = SufficientStats(
        start=gamma[:, 0],
        trans=xi,
        counts=counts,
        first=first,
        second=second,
        loglik=loglik.copy(),
        weight=np.ones(K),
        frames=np.full(K, float(T)),
    )
    return stats, loglik


def _raw_moments(moments: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Counts, first and second raw moments from ``Σ p φ(x − centre)`` (shape (..., P)): the moments about
    the centre moved back to the origin."""
    D = len(centre)
    pairs = _pairs(D)
    counts = moments[..., -1]
    first_c = moments[..., len(pairs) : len(pairs) + D]
    second_c = np.empty(moments.shape[:-1] + (D, D))
    for k, (i, j) in enumerate(pairs):
        second_c[..., i, j] = second_c[..., j, i] = moments[..., k]
    first = first_c + counts[..., None] * centre
    cross = first_c[..., :, None] * centre
    second = (
        second_c + cross + np.swapaxes(cross, -1, -2) + counts[..., None, None] * np.outer(centre, centre)
    )
    return counts, first, second


class _Prepared(NamedTuple):
    """Weighted sequences laid out once for many E-steps (everything that does not depend on the model)."""

    w: np.ndarray  # (S,) the positive weights
    lengths: np.ndarray  # (S,)
    alive: np.ndarray  # (S, T) real frames
    centre: np.ndarray  # (D,) the frames' mean
    phi: np.ndarray  # (N, P) their quadratic monomials about the centre
    frame_w: np.ndarray  # (N,) each frame's sequence weight


def _prepare(sequences: Sequence[np.ndarray], weights: np.ndarray | None) -> _Prepared | None:
    w = sequence_weights(sequences, weights)
    keep = np.flatnonzero(w > 0)
    if len(keep) == 0:
        return None
    seqs, w = [np.asarray(sequences[i], dtype=float) for i in keep], w[keep]
    lengths = np.array([len(x) for x in seqs])
    X = np.concatenate(seqs)
    centre = X.mean(axis=0)
    alive = np.arange(int(lengths.max()))[None, :] < lengths[:, None]
    return _Prepared(w, lengths, alive, centre, quadratic_features(X, centre), np.repeat(w, lengths))


def _estep(prep: _Prepared, params: GMMHMMParams) -> SufficientStats:
    Q, M, _ = params.means.shape
    S, T = prep.alive.shape
    N = len(prep.phi)
    chol_inv, log_norm = gaussian_factors(params.weights, params.covars)
    lc = (prep.phi @ _coefficients(params.means - prep.centre, chol_inv, log_norm)).reshape(N, Q, M)
    log_b_flat = lc[..., 0] if M == 1 else _logsumexp(lc, axis=-1)  # (N, Q)
    log_b = np.zeros((S, T, Q))
    log_b[prep.alive] = log_b_flat
    pi = np.broadcast_to(params.startprob, (S, Q))
    A = np.broadcast_to(params.transmat, (S, Q, Q))
    gamma, xi, loglik, ok = forward_backward_scaled(log_b, prep.lengths, pi, A)
    for k in np.flatnonzero(~ok):  # the scaled mass underflowed: this sequence in the log domain
        g, x, ll = forward_backward_log(
            np.where(prep.alive[k : k + 1, :, None], log_b[k : k + 1], -np.inf),
            prep.lengths[k : k + 1],
            params.startprob,
            params.transmat,
        )
        gamma[k], xi[k], loglik[k] = g[0], x, ll[0]
    with np.errstate(under="ignore"):
        post_mix = np.ones_like(lc) if M == 1 else np.exp(lc - log_b_flat[..., None])
    pcm = (gamma[prep.alive] * prep.frame_w[:, None])[..., None] * post_mix  # (N, Q, M)
    counts, first, second = _raw_moments((pcm.reshape(N, -1).T @ prep.phi).reshape(Q, M, -1), prep.centre)
    w = prep.w
    return SufficientStats(
        start=w @ gamma[:, 0],
        trans=np.tensordot(w, xi, axes=1),
        counts=counts,
        first=first,
        second=second,
        loglik=np.asarray(float(w @ loglik)),
        weight=np.asarray(float(w.sum())),
        frames=np.asarray(float(w @ prep.lengths)),
    )


def expected_stats_fast(
    sequences: Sequence[np.ndarray], params: GMMHMMParams, weights: np.ndarray | None = None
) -> SufficientStats:
    """:func:`glu.hmm.em.expected_stats` (many sequences, one model), the recursions compiled: equal to it
    to rounding (tested). A few short sequences — the first model of an online learner — cost a
    fraction of the array code's per-frame dispatch."""
    prep = _prepare(sequences, weights)
    if prep is None:
        return SufficientStats.zeros(*params.means.shape)
    return _estep(prep, params)


def fit_weighted_fast(
    sequences: Sequence[np.ndarray],
    weights: np.ndarray | None,
    init: GMMHMMParams,
    n_iter: int,
    tol: float,
    covar_reg: float = 0.0,
    covariance: str = "map",
    covar_floor: float = 0.0,
) -> FitResult:
    """:func:`glu.hmm.em.fit_weighted` with the E-step of :func:`expected_stats_fast` (equal to rounding)."""
    prep = _prepare(sequences, weights)
    if prep is None:
        raise ValueError("weighted EM needs at least one sequence of positive weight")
    options = {"covar_reg": covar_reg, "covariance": covariance, "covar_floor": covar_floor}
    return iterate(lambda p: _estep(prep, p), init, n_iter, tol, **options)


def _pairs(D: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(D) for j in range(i, D)]


def _coefficients(means: np.ndarray, chol_inv: np.ndarray, log_norm: np.ndarray) -> np.ndarray:
    """Coefficients on :func:`~glu.hmm._engine.batch.quadratic_features` of every component's
    ``log w + log N(x; μ, Σ)``, shape (P, K·Q·M), for means already centred (shape (K, Q, M, D))."""
    P = np.swapaxes(chol_inv, -1, -2) @ chol_inv  # Σ⁻¹ = L⁻ᵀ L⁻¹
    b = np.einsum("...ij,...j->...i", P, means)
    const = log_norm - 0.5 * np.einsum("...i,...i->...", means, b)
    D = means.shape[-1]
    rows = [(-0.5 if i == j else -1.0) * P[..., i, j] for i, j in _pairs(D)]
    rows += [b[..., i] for i in range(D)] + [const]
    return np.stack([r.reshape(-1) for r in rows], axis=0)


def _forward_scaled(log_b, startprob, transmat):
    """The scaled forward recursion of each of K models over one sequence's emissions ``log_b`` (K, T, Q):
    ``log L`` (K,) and whether the scaled mass stayed above TINY at every frame (K,) (compiled)."""
    K, T, Q = log_b.shape
    loglik = np.zeros(K)
    ok = np.ones(K, dtype=np.bool_)
    alpha = np.empty(Q)
    new = np.empty(Q)
    b = np.empty(Q)
    for k in range(K):
        A = transmat[k]
        for t in range(T):
            mx = -np.inf
            for j in range(Q):
                if log_b[k, t, j] > mx:
                    mx = log_b[k, t, j]
            for j in range(Q):
                b[j] = np.exp(log_b[k, t, j] - mx)
            total = 0.0
            for j in range(Q):
                if t == 0:
                    v = startprob[k, j] * b[j]
                else:
                    acc = 0.0
                    for i in range(Q):
                        acc += alpha[i] * A[i, j]
                    v = acc * b[j]
                new[j] = v
                total += v
            if not total > TINY:
                ok[k] = False
                break
            loglik[k] += np.log(total) + mx
            for j in range(Q):
                alpha[j] = new[j] / total
    return loglik, ok
