"""The fast EM: weighted Baum–Welch for a batch of GMM-HMMs, each model with its own weighted sequences.

This is the one fast implementation of the E-step and of EM (:mod:`glu.hmm.em` is its readable
reference, the tests' oracle). Every trainer runs on it: one model is a batch of one, unweighted EM has
every weight 1.

* :class:`Layout` lays the sequences of every model out once, whatever the model's parameters: each
  model's frames in order (padded to the model with most frames), centred on that model's mean frame and
  expanded into the monomials ``φ(x) = (x_i x_j for i ≤ j, x_i, 1)`` (:func:`quadratic_features`);
  sequences of weight 0 are left out;
* :func:`estep` is the E-step of every model at once: every component's ``log w + log N(x; μ, Σ)`` is
  ``φ(x) · c`` (:func:`quadratic_coefficients`, one matrix product per model); the forward–backward
  recursions run compiled, one sequence at a time (:func:`glu.hmm._engine.kernels.forward_backward_scaled`);
  a sequence whose scaled mass underflows is redone alone in the log domain
  (:func:`glu.hmm.inference.forward_backward_log`); the sufficient statistics (soft counts, first and
  second moments, each frame times its sequence's weight) are one product of the responsibilities with
  ``φ``, about each model's centre, which keeps the scatter ``Σ p x xᵀ − m sᵀ − s mᵀ + N m mᵀ`` far from
  cancellation;
* :func:`fit_many` is EM: :func:`estep`, then :func:`glu.hmm.em.maximise` (the M-step, run in the centred
  coordinates) until each model converges (the same ``tol`` rule and ``n_iter`` cap as
  :func:`glu.hmm.em.fit`); a converged model's parameters freeze and its sequences leave the batch;
* :func:`expected_stats_many` gives :func:`estep`'s statistics about the origin (raw moments, which add up
  across sequences and episodes): the E-step of online learning.

Results equal :func:`glu.hmm.em.fit` and :func:`glu.hmm.em.expected_stats` for each model to rounding
(summation order): the same number of iterations, log-likelihood histories to 1e-10 and parameters to
1e-8 relative (``tests/library/test_baum_welch_batch.py``, ``tests/library/test_weighted_em.py``). Models
of different shapes (Q, M, D) are grouped and each group runs as one batch.

Example
-------
>>> import numpy as np
>>> from glu.hmm.em import GMMHMMParams, fit
>>> rng = np.random.default_rng(0)
>>> def problem(shift):
...     seqs = [rng.normal(shift, 1.0, size=(n, 2)) for n in (20, 30)]
...     A = np.array([[0.9, 0.1], [0.0, 1.0]])
...     init = GMMHMMParams(np.array([1.0, 0.0]), A, np.ones((2, 1)), rng.normal(size=(2, 1, 2)),
...                         np.tile(np.eye(2), (2, 1, 1, 1)))
...     return seqs, init
>>> problems = [problem(0.0), problem(3.0)]
>>> batched = fit_many(problems, n_iter=20, tol=1e-3, covar_reg=0.01)
>>> alone = [fit(s, i, 20, 1e-3, 0.01) for s, i in problems]
>>> [len(r.history) for r in batched] == [len(r.history) for r in alone]
True
>>> all(np.allclose(b.params.means, a.params.means, rtol=1e-8) for b, a in zip(batched, alone))
True
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from glu.errors import ModelError
from glu.hmm._engine.kernels import forward_backward_scaled, mixture_posteriors
from glu.hmm.em import (
    FitResult,
    GMMHMMParams,
    SufficientStats,
    check_covariance,
    maximise,
    sequence_weights,
)
from glu.hmm.inference import forward_backward_log, gaussian_factors

MAX_BATCH_FLOATS = 4_000_000
"""Models are batched in chunks whose (model, component, frame, feature) arrays hold about this many floats
(32 MB each): more models per batch gain little once a chunk has a few dozen."""


def monomial_pairs(D: int) -> list[tuple[int, int]]:
    """The index pairs ``(i, j), i ≤ j`` of the quadratic monomials, in :func:`quadratic_features`' order."""
    return [(i, j) for i in range(D) for j in range(i, D)]


def quadratic_features(X: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """``φ(x − centre)``: the monomials ``x_i x_j`` (i ≤ j), ``x_i`` and 1 of each frame, shape (..., N, F)
    with ``F = D(D+1)/2 + D + 1``, for frames ``X`` of shape (..., N, D)."""
    Z = np.asarray(X, dtype=float) - centre
    D = Z.shape[-1]
    cols = [Z[..., i] * Z[..., j] for i, j in monomial_pairs(D)] + [Z[..., i] for i in range(D)]
    return np.stack(cols + [np.ones(Z.shape[:-1])], axis=-1)


def quadratic_coefficients(means: np.ndarray, chol_inv: np.ndarray, log_norm: np.ndarray) -> np.ndarray:
    """Every component's ``log w + log N(x; μ, Σ)`` as coefficients on :func:`quadratic_features`.

    ``means`` (..., D) already centred (μ − centre), ``chol_inv`` (..., D, D) and ``log_norm`` (...) from
    :func:`glu.hmm.inference.gaussian_factors`; returns shape (..., F): ``φ(x − centre) · coef`` is
    ``log w − ½ (x − μ)ᵀ Σ⁻¹ (x − μ) − (D/2) log 2π − ½ log |Σ|``.
    """
    prec = np.swapaxes(chol_inv, -1, -2) @ chol_inv  # Σ⁻¹ = L⁻ᵀ L⁻¹
    lin = np.einsum("...ij,...j->...i", prec, means)
    with np.errstate(invalid="ignore"):
        const = log_norm - 0.5 * np.einsum("...i,...i->...", means, lin)
    D = means.shape[-1]
    rows = [(-0.5 if i == j else -1.0) * prec[..., i, j] for i, j in monomial_pairs(D)]
    return np.stack(rows + [lin[..., i] for i in range(D)] + [const], axis=-1)


class Layout:
    """The weighted sequences of a batch of models laid out once for many E-steps.

    Parameters
    ----------
    sequences : per model, its sequences (arrays of shape (T_i, D), the same D for all)
    weights : per model, one weight ≥ 0 per sequence; sequences of weight 0 are left out, and every model
        needs one of positive weight (ModelError otherwise)
    """

    def __init__(self, sequences: Sequence[Sequence[np.ndarray]], weights: Sequence[np.ndarray]) -> None:
        kept = []
        for seqs, w in zip(sequences, weights, strict=True):
            pairs = [(np.asarray(x, dtype=float), float(v)) for x, v in zip(seqs, w, strict=True) if v > 0]
            if not pairs:
                raise ModelError("weighted EM needs at least one sequence of positive weight")
            kept.append(pairs)
        K = len(kept)
        self.n_frames = np.array([sum(len(x) for x, _ in p) for p in kept])
        N, D = int(self.n_frames.max()), kept[0][0][0].shape[1]
        X = np.zeros((K, N, D))  # (model, frame): each model's frames in order, zero-padded
        self.centre = np.zeros((K, D))  # each model's mean frame: the moments are taken about it
        self.frame_w = np.zeros((K, N))  # each frame's sequence weight (0 for padding)
        model, first, length, weight = [], [], [], []
        for k, pairs in enumerate(kept):
            frames = np.concatenate([x for x, _ in pairs])
            self.centre[k] = frames.mean(axis=0)
            X[k, : self.n_frames[k]] = frames - self.centre[k]
            offset = 0
            for x, w in pairs:
                self.frame_w[k, offset : offset + len(x)] = w
                model.append(k), first.append(k * N + offset), length.append(len(x)), weight.append(w)
                offset += len(x)
        # the sequences longest first (the compiled recursions run a little faster so); position[i] is where
        # the i-th sequence given (model after model) stands
        order = np.lexsort((np.arange(len(length)), -np.array(length)))
        self.position = np.empty(len(order), dtype=int)
        self.position[order] = np.arange(len(order))
        self.model, self.lengths = np.array(model)[order], np.array(length)[order]
        self.weight = np.array(weight)[order]
        self.unit_weights = bool(np.all(self.weight == 1.0))
        self.members = (self.model[None, :] == np.arange(K)[:, None]).astype(float)  # (K, S): sums per model
        alive = np.arange(N)[None, :] < self.n_frames[:, None]
        self.phi = quadratic_features(X, 0.0) * alive[..., None]  # (K, N, F); padding frames are zero
        T = int(self.lengths.max())
        self.alive = np.arange(T)[None, :] < self.lengths[:, None]  # (S, T)
        # flat index into (K·N) of frame t of sequence s (padding points at frame 0 of the batch: ignored)
        self.index = np.where(self.alive, np.array(first)[order][:, None] + np.arange(T)[None, :], 0)

    @property
    def n_models(self) -> int:
        """K."""
        return len(self.centre)

    def centred(self, params: GMMHMMParams) -> GMMHMMParams:
        """Stacked parameters (leading axis K) with each model's means moved to its centre."""
        return params._replace(means=params.means - self.centre[:, None, None, :])

    def uncentred(self, params: GMMHMMParams) -> GMMHMMParams:
        """:meth:`centred` undone."""
        return params._replace(means=params.means + self.centre[:, None, None, :])


def estep(layout: Layout, params: GMMHMMParams) -> tuple[SufficientStats, np.ndarray]:
    """The E-step of every model of ``layout`` under its parameters, in one pass.

    ``params`` are stacked (leading axis K, the layout's models) with means *centred*
    (:meth:`Layout.centred`). Returns the weighted :class:`~glu.hmm.em.SufficientStats` of each model,
    batch shape (K,), with moments about the model's centre (``first`` and ``second`` of the centred
    frames), and ``log L`` of each sequence of positive weight (unweighted), shape (S,), model after model
    in the order given to the layout. Raises
    ``numpy.linalg.LinAlgError`` if a used covariance is not positive definite.
    """
    startprob, transmat, weights, means, covars = params
    K, N, F = layout.phi.shape
    Q, M = weights.shape[1:]
    D = means.shape[-1]
    chol_inv, log_norm = gaussian_factors(weights, covars)  # (K, Q, M, D, D), (K, Q, M)
    coef = quadratic_coefficients(means, chol_inv, log_norm).reshape(K, Q * M, F)
    lc = (layout.phi @ np.swapaxes(coef, 1, 2)).reshape(K, N, Q, M)
    log_b_frames, post_mix = (lc[..., 0], None) if M == 1 else mixture_posteriors(lc)
    log_b = log_b_frames.reshape(K * N, Q)[layout.index]  # (S, T, Q)
    seq_model, lengths, w = layout.model, layout.lengths, layout.weight
    gamma, xi, loglik, ok = forward_backward_scaled(log_b, lengths, startprob[seq_model], transmat[seq_model])
    for s in np.flatnonzero(~ok):  # the scaled mass underflowed: this sequence alone, in the log domain
        k, T_s = seq_model[s], lengths[s]
        g, x, ll = forward_backward_log(log_b[s : s + 1, :T_s], lengths[s : s + 1], startprob[k], transmat[k])
        gamma[s, :T_s], xi[s], loglik[s] = g[0], x, ll[0]
    gamma_frames = np.zeros((K * N, Q))  # padding frames: zero responsibility
    gamma_frames[layout.index[layout.alive]] = gamma[layout.alive]
    gamma_frames = gamma_frames.reshape(K, N, Q)
    if not layout.unit_weights:
        gamma_frames *= layout.frame_w[..., None]
    pcm = gamma_frames[..., None] if post_mix is None else gamma_frames[..., None] * post_mix
    # every moment at once: Σ p·x_i x_j, Σ p·x_i, Σ p per component (K, Q, M, F)
    moments = (np.swapaxes(pcm.reshape(K, N, Q * M), 1, 2) @ layout.phi).reshape(K, Q, M, F)
    pairs = monomial_pairs(D)
    second = np.empty((K, Q, M, D, D))
    for f, (i, j) in enumerate(pairs):
        second[..., i, j] = second[..., j, i] = moments[..., f]

    def per_model(values: np.ndarray) -> np.ndarray:  # Σ over each model's sequences
        """``values``, shape (S, ...), one row per sequence of the layout → their sums, shape (K, ...)."""
        return (layout.members @ values.reshape(len(values), -1)).reshape((K,) + values.shape[1:])

    stats = SufficientStats(
        start=per_model(w[:, None] * gamma[:, 0]),
        trans=per_model(w[:, None, None] * xi),
        counts=moments[..., -1],
        first=moments[..., len(pairs) : len(pairs) + D],
        second=second,
        loglik=per_model(w * loglik),
        weight=per_model(w),
        frames=per_model(w * lengths),
    )
    return stats, loglik[layout.position]


def about_origin(stats: SufficientStats, centre: np.ndarray) -> SufficientStats:
    """Statistics with moments about ``centre`` (shape (K, D), one per model) moved to the origin: the raw
    moments ``Σ p x`` and ``Σ p x xᵀ`` of :mod:`glu.hmm.em`."""
    c = centre[:, None, None, :]  # (K, 1, 1, D)
    first = stats.first + stats.counts[..., None] * c
    cross = stats.first[..., :, None] * c[..., None, :]
    second = (
        stats.second
        + cross
        + np.swapaxes(cross, -1, -2)
        + stats.counts[..., None, None] * (c[..., :, None] * c[..., None, :])
    )
    return replace(stats, first=first, second=second)


def expected_stats_many(
    sequences: Sequence[Sequence[np.ndarray]], params: GMMHMMParams, weights: Sequence[np.ndarray]
) -> tuple[SufficientStats, np.ndarray]:
    """:func:`glu.hmm.em.expected_stats` of many models at once, each over its own weighted sequences.

    ``params`` stacked (leading axis K, the models, means about the origin); ``sequences[k]`` and
    ``weights[k]`` are model k's. Returns the statistics (batch shape (K,), raw moments) and ``log L`` of
    each sequence of positive weight, model after model in the given order, shape (S,).
    """
    layout = Layout(sequences, weights)
    stats, loglik = estep(layout, layout.centred(params))
    return about_origin(stats, layout.centre), loglik


def fit_many(
    problems: Sequence[tuple[Sequence[np.ndarray], GMMHMMParams]],
    n_iter: int,
    tol: float | Sequence[float],
    covar_reg: float = 0.0,
    covariance: str = "map",
    covar_floor: float = 0.0,
    weights: Sequence[Sequence[float] | None] | None = None,
    progress: Callable[[int], None] | None = None,
) -> list[FitResult]:
    """Fit many GMM-HMMs, each to its own weighted sequences, by Baum–Welch in one batch.

    Parameters
    ----------
    problems : (sequences, init) per model: arrays of shape (T_i, D) and the starting
        :class:`~glu.hmm.em.GMMHMMParams`; models of different (Q, M, D) run in separate batches
    n_iter : most EM iterations, per model
    tol : the stopping tolerance on each model's total (weighted) log-likelihood (one for all, or one per
        model)
    covar_reg, covariance, covar_floor : as :func:`~glu.hmm.em.fit`
    weights : per model, one weight ≥ 0 per sequence (None: all 1; sequences of weight 0 are left out)
    progress : called with the number of models that have just stopped, after each iteration

    Returns
    -------
    one :class:`~glu.hmm.em.FitResult` per problem, in order, equal to what :func:`~glu.hmm.em.fit` returns
    for it (to rounding). Raises ``numpy.linalg.LinAlgError`` when a covariance stops being positive
    definite, ModelError for bad weights.
    """
    check_covariance(covariance)
    tols = np.broadcast_to(np.asarray(tol, dtype=float), (len(problems),))
    ws = [None] * len(problems) if weights is None else list(weights)
    items = [
        (
            [np.asarray(x, dtype=float) for x in seqs],
            GMMHMMParams(*(np.array(a, dtype=float) for a in init)),
            sequence_weights(seqs, w),
        )
        for (seqs, init), w in zip(problems, ws, strict=True)
    ]
    groups: dict[tuple[int, ...], list[int]] = {}
    for k, (seqs, init, _) in enumerate(items):
        groups.setdefault((*init.weights.shape, seqs[0].shape[1]), []).append(k)
    out: list[FitResult | None] = [None] * len(items)
    mstep = {"covar_reg": covar_reg, "covariance": covariance, "covar_floor": covar_floor}
    for (Q, M, D), ks in groups.items():
        for chunk in _chunks(ks, [sum(len(x) for x in items[k][0]) for k in ks], Q * M * D):
            results = _fit_group([items[k] for k in chunk], n_iter, tols[chunk], mstep, progress)
            for k, r in zip(chunk, results, strict=True):
                out[k] = r
    return out  # type: ignore[return-value]


def _chunks(keys: list[int], frames: list[int], width: int) -> list[list[int]]:
    """``keys`` in chunks whose (model, component, frame, feature) arrays hold about
    :data:`MAX_BATCH_FLOATS` floats."""
    chunks: list[list[int]] = [[]]
    widest = 0
    for k, n in zip(keys, frames, strict=True):
        if chunks[-1] and (len(chunks[-1]) + 1) * max(widest, n) * width > MAX_BATCH_FLOATS:
            chunks.append([])
            widest = 0
        chunks[-1].append(k)
        widest = max(widest, n)
    return chunks


def _fit_group(
    problems: list[tuple[list[np.ndarray], GMMHMMParams, np.ndarray]],
    n_iter: int,
    tols: np.ndarray,
    mstep: dict,
    progress: Callable[[int], None] | None,
) -> list[FitResult]:
    """:func:`fit_many` for models of one shape: every model's parameters stacked, centred on its frames."""
    P = len(problems)
    everything = Layout([p[0] for p in problems], [p[2] for p in problems])
    params = everything.centred(
        GMMHMMParams(*(np.stack(a) for a in zip(*(p[1] for p in problems), strict=True)))
    )
    histories: list[list[float]] = [[] for _ in range(P)]
    live = list(range(P))
    layout = everything
    for _ in range(n_iter):
        ix = np.array(live)
        if len(live) != layout.n_models:  # a model stopped: lay out the others again
            layout = Layout([problems[k][0] for k in live], [problems[k][2] for k in live])
        current = GMMHMMParams(*(a[ix] for a in params))
        stats, _ = estep(layout, current)
        for i, k in enumerate(live):
            histories[k].append(float(stats.loglik[i]))
        for a, new in zip(params, maximise(stats, current, **mstep), strict=True):
            a[ix] = new
        stopped = [
            k for k in live if len(histories[k]) >= 2 and histories[k][-1] - histories[k][-2] < tols[k]
        ]
        live = [k for k in live if k not in stopped]
        if progress is not None and stopped:
            progress(len(stopped))
        if not live:
            break
    if progress is not None and live:
        progress(len(live))  # stopped at n_iter
    final = everything.uncentred(params)
    return [FitResult(GMMHMMParams(*(a[k] for a in final)), np.array(histories[k])) for k in range(P)]
