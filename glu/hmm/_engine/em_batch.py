"""Baum–Welch for many independent GMM-HMMs at once: one padded batch of every model's sequences.

Experiments train many small models (leave-one-segment-out folds, k-fold cross-validation, one model per
action and feature set and seed); :func:`glu.hmm.em.fit` trains one. :func:`fit_many` runs
the models side by side:

* the sequences of every model form one batch, sorted by length (longest first), each with its model's
  transition matrix; the forward and backward recursions run compiled, one sequence at a time
  (:func:`glu.hmm._engine.kernels.forward_backward_scaled`, via :func:`forward_backward_many`), since as
  array code their cost was per-frame dispatch that hardly depended on the number of sequences;
* the emission densities and the M-step are array operations over a (model, frame) layout, frames
  padded to the model with most frames (padding has zero responsibility). Each frame is centred on its
  model's mean frame and expanded into its monomials ``φ(x) = (x_i x_j for i ≤ j, x_i, 1)`` once; every
  component's ``log w + log N(x; μ, Σ)`` is then ``φ(x) · c`` (one matrix product per model), and the
  M-step's sufficient statistics (soft counts, first and second moments) are one product of the
  responsibilities with ``φ``; the scatter about a mean ``m`` is ``Σ p x xᵀ − m sᵀ − s mᵀ + N m mᵀ``
  (s the first moment, N the count), which the centring keeps far from cancellation;
* each model stops exactly as :func:`~glu.hmm.em.fit` would (same ``tol`` rule, same
  ``n_iter`` cap): once converged its parameters freeze and its sequences leave the batch;
* the scaled recursion is checked for underflow once per pass; a model with a sequence whose scaled mass
  underflowed is redone alone in the log domain (:func:`~glu.hmm.em.forward_backward_log`),
  exactly as ``fit`` redoes its batch, while the other models keep their scaled results.

The results equal ``[fit(seqs, init, …) for seqs, init in problems]`` to rounding (summation order):
the same number of iterations, log-likelihood histories to 1e-10 and parameters to 1e-8 relative
(``tests/test_baum_welch_batch.py``). Models of different shapes (Q, M, D) are grouped and each group runs
as one batch.

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

from collections.abc import Sequence

import numpy as np

from glu.hmm._engine.kernels import forward_backward_scaled, mixture_posteriors
from glu.hmm.em import COVARIANCES, EMPTY, FitResult, GMMHMMParams
from glu.hmm.inference import forward_backward_log, gaussian_factors

MAX_BATCH_FLOATS = 4_000_000
"""Models are batched in chunks whose (model, component, frame, feature) arrays hold about this many floats
(32 MB each): more models per batch gain little once a chunk has a few dozen."""


def forward_backward_many(
    log_b: np.ndarray, lengths: np.ndarray, startprob: np.ndarray, transmat: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Scaled forward–backward over a padded batch whose sequences each have their own parameters.

    Parameters
    ----------
    log_b : array, shape (S, T, Q) — emission log-densities; entries past a sequence's length are ignored
    lengths : array, shape (S,) — sequence lengths, sorted in decreasing order (≥ 1)
    startprob : array, shape (S, Q) — each sequence's initial distribution
    transmat : array, shape (S, Q, Q) — each sequence's transition matrix

    Returns
    -------
    gamma : array, shape (S, T, Q) — ``P(q_t | G)`` (0 past a sequence's end)
    xi : array, shape (S, Q, Q) — each sequence's expected transition counts
    loglik : array, shape (S,) — ``log L(G)``
    ok : array of bool, shape (S,) — False where the scaled mass underflowed at some frame (those
        sequences' other outputs are meaningless: redo them in the log domain)

    The recursions run compiled, one sequence at a time
    (:func:`glu.hmm._engine.kernels.forward_backward_scaled`); a sequence stops at its first underflow.
    """
    if np.any(np.diff(lengths) > 0):
        raise ValueError("forward_backward_many: lengths must be sorted in decreasing order")
    return forward_backward_scaled(log_b, lengths, startprob, transmat)


def _pairs(D: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(D) for j in range(i, D)]


class _Batch:
    """The live models' data laid out for one EM iteration (rebuilt when a model leaves)."""

    def __init__(self, problems: list[tuple[list[np.ndarray], GMMHMMParams]], live: list[int]) -> None:
        self.live = live
        K = len(live)
        seqs = [problems[k][0] for k in live]
        self.n_frames = np.array([sum(len(x) for x in s) for s in seqs])
        N = int(self.n_frames.max())
        D = seqs[0][0].shape[1]
        self.X = np.zeros((K, N, D))  # (model, frame): each model's frames in order, zero-padded
        self.frame_alive = np.arange(N)[None, :] < self.n_frames[:, None]
        model, first, length = [], [], []
        self.centre = np.zeros((K, D))  # each model's mean frame: the moments are taken about it
        for i, s in enumerate(seqs):
            frames = np.concatenate(s)
            self.centre[i] = frames.mean(axis=0)
            self.X[i, : self.n_frames[i]] = frames - self.centre[i]
            offsets = np.concatenate([[0], np.cumsum([len(x) for x in s])[:-1]])
            for j, x in enumerate(s):
                model.append(i), first.append(i * N + offsets[j]), length.append(len(x))
        order = np.lexsort((np.arange(len(length)), -np.array(length)))  # longest first, stable
        self.model = np.array(model)[order]  # (S,) index into the live models
        self.lengths = np.array(length)[order]
        first = np.array(first)[order]
        # the monomials x_i x_j (i ≤ j), x_i, 1 of each centred frame (0 for padding), shape (K, N, F)
        pairs = _pairs(D)
        cols = [self.X[..., i] * self.X[..., j] for i, j in pairs] + [self.X[..., i] for i in range(D)]
        self.phi = np.stack(cols + [self.frame_alive.astype(float)], axis=-1)
        T = int(self.lengths.max())
        self.alive = np.arange(T)[None, :] < self.lengths[:, None]  # (S, T)
        # flat index into (K·N) of frame t of sequence s (padding points at frame 0 of the batch: ignored)
        self.index = np.where(self.alive, first[:, None] + np.arange(T)[None, :], 0)
        # each model's sequences, in the caller's order (for the log-domain redo and the history)
        seq_pos = np.empty(len(order), dtype=int)
        seq_pos[order] = np.arange(len(order))
        self.seqs_of = [[] for _ in range(K)]
        for pos_orig, i in enumerate(model):
            self.seqs_of[i].append(seq_pos[pos_orig])
        self.seqs_of = [np.array(ix) for ix in self.seqs_of]


def fit_many(
    problems: Sequence[tuple[Sequence[np.ndarray], GMMHMMParams]],
    n_iter: int,
    tol: float | Sequence[float],
    covar_reg: float = 0.0,
    covariance: str = "map",
    covar_floor: float = 0.0,
) -> list[FitResult]:
    """Fit many GMM-HMMs, each to its own sequences, by Baum–Welch in one batch.

    Parameters
    ----------
    problems : (sequences, init) per model: arrays of shape (T_i, D) and the starting
        :class:`~glu.hmm.em.GMMHMMParams`; models of different (Q, M, D) run in separate
        batches
    n_iter : most EM iterations, per model
    tol : the stopping tolerance on each model's total log-likelihood (one for all, or one per model)
    covar_reg, covariance, covar_floor : as :func:`~glu.hmm.em.fit`

    Returns
    -------
    one :class:`~glu.hmm.em.FitResult` per problem, in order, equal to what
    :func:`~glu.hmm.em.fit` returns for it (to rounding). Raises
    ``numpy.linalg.LinAlgError`` when a covariance stops being positive definite.
    """
    if covariance not in COVARIANCES:
        raise ValueError(f"unknown covariance update {covariance!r}; allowed: {', '.join(COVARIANCES)}")
    tols = np.broadcast_to(np.asarray(tol, dtype=float), (len(problems),))
    items = [
        ([np.asarray(x, dtype=float) for x in seqs], GMMHMMParams(*(np.array(a, dtype=float) for a in init)))
        for seqs, init in problems
    ]
    groups: dict[tuple[int, ...], list[int]] = {}
    for k, (seqs, init) in enumerate(items):
        groups.setdefault((*init.weights.shape, seqs[0].shape[1]), []).append(k)
    out: list[FitResult | None] = [None] * len(items)
    for (Q, M, D), ks in groups.items():
        chunks: list[list[int]] = [[]]
        widest = 0
        for k in ks:  # bound the (model, component, frame) arrays: about MAX_BATCH_FLOATS floats each
            n = sum(len(x) for x in items[k][0])
            if chunks[-1] and (len(chunks[-1]) + 1) * max(widest, n) * Q * M * D > MAX_BATCH_FLOATS:
                chunks.append([])
                widest = 0
            chunks[-1].append(k)
            widest = max(widest, n)
        for chunk in chunks:
            results = _fit_group(
                [items[k] for k in chunk], n_iter, tols[chunk], covar_reg, covariance, covar_floor
            )
            for k, r in zip(chunk, results, strict=True):
                out[k] = r
    return out  # type: ignore[return-value]


def _fit_group(
    problems: list[tuple[list[np.ndarray], GMMHMMParams]],
    n_iter: int,
    tols: np.ndarray,
    covar_reg: float,
    covariance: str,
    covar_floor: float,
) -> list[FitResult]:
    """:func:`fit_many` for models of one shape."""
    P = len(problems)
    # every model's current parameters, stacked: (P, Q), (P, Q, Q), (P, Q, M), (P, Q, M, D), (P, Q, M, D, D)
    params = [np.stack([p[1][i] for p in problems]) for i in range(5)]
    Q, M = params[2].shape[1:]
    D = params[3].shape[-1]
    pairs = _pairs(D)
    histories: list[list[float]] = [[] for _ in range(P)]
    live = list(range(P))
    batch = _Batch(problems, live)
    for _ in range(n_iter):
        if batch.live != live:
            batch = _Batch(problems, live)
        ix = np.array(live)
        startprob, transmat, weights, means, covars = (a[ix] for a in params)
        K, N = batch.X.shape[:2]
        chol_inv, log_norm = gaussian_factors(weights, covars)  # (K, Q, M, D, D), (K, Q, M)
        # log w + log N(x; μ, Σ) of every frame and component as one product with the frames' monomials:
        # −½ xᵀPx + (Pμ)ᵀx − ½ μᵀPμ + log-normaliser, P = Σ⁻¹, in coordinates centred on each model's frames
        prec = np.swapaxes(chol_inv, -1, -2) @ chol_inv
        mu = means - batch.centre[:, None, None, :]
        lin = (prec @ mu[..., None])[..., 0]  # (K, Q, M, D)
        with np.errstate(invalid="ignore"):
            const = log_norm - 0.5 * (mu * lin).sum(axis=-1)
        coef = np.stack(
            [(-0.5 if i == j else -1.0) * prec[..., i, j] for i, j in pairs]
            + [lin[..., i] for i in range(D)]
            + [const],
            axis=-1,
        )  # (K, Q, M, F)
        lc = (batch.phi @ np.swapaxes(coef.reshape(K, Q * M, -1), 1, 2)).reshape(K, N, Q, M)
        # each state's emission log-density (K, N, Q) and its mixture's responsibilities, in one pass
        if M == 1:
            log_b_frames, post_mix = lc[..., 0], None
        else:
            log_b_frames, post_mix = mixture_posteriors(lc)
        log_b = log_b_frames.reshape(K * N, Q)[batch.index]  # (S, T, Q)
        seq_model = batch.model
        gamma, xi, loglik, ok = forward_backward_many(
            log_b, batch.lengths, startprob[seq_model], transmat[seq_model]
        )
        xi_sum = np.zeros((K, Q, Q))
        np.add.at(xi_sum, seq_model, xi)
        for i in np.unique(seq_model[~ok]):  # underflow: this model's batch again, in the log domain
            s = batch.seqs_of[i]
            T_i = int(batch.lengths[s].max())
            g, xs, ll = forward_backward_log(log_b[s, :T_i], batch.lengths[s], startprob[i], transmat[i])
            gamma[s, :T_i], xi_sum[i], loglik[s] = g, xs, ll
        for i, k in enumerate(live):
            histories[k].append(float(loglik[batch.seqs_of[i]].sum()))
        gamma_frames = np.zeros((K * N, Q))  # padding frames: zero responsibility
        gamma_frames[batch.index[batch.alive]] = gamma[batch.alive]
        gamma_frames = gamma_frames.reshape(K, N, Q)
        # the components' responsibilities (0 on padding frames, whose gamma is 0 and whose lc is 0)
        pcm = gamma_frames[..., None] if post_mix is None else gamma_frames[..., None] * post_mix
        # every sufficient statistic at once: Σ pcm·x_i x_j, Σ pcm·x_i, Σ pcm per component
        moments = (np.swapaxes(pcm.reshape(K, N, Q * M), 1, 2) @ batch.phi).reshape(K, Q, M, -1)
        second = np.empty((K, Q, M, D, D))
        for f, (i, j) in enumerate(pairs):
            second[..., i, j] = second[..., j, i] = moments[..., f]
        m_n = moments[..., len(pairs) : len(pairs) + D]  # (K, Q, M, D), centred
        post_mix_sum = moments[..., -1]  # (K, Q, M)
        start = np.zeros((K, Q))
        np.add.at(start, seq_model, gamma[:, 0])
        post_sum = gamma_frames.sum(axis=1)  # (K, Q)
        # M-step, as fit's
        new_start = np.where(startprob == 0, 0.0, np.maximum(start, 0.0))
        new_start = new_start / new_start.sum(axis=1, keepdims=True)
        new_trans = np.where(transmat == 0, 0.0, np.maximum(xi_sum, 0.0))
        row = new_trans.sum(axis=2, keepdims=True)
        new_trans = new_trans / np.where(row == 0, 1.0, row)
        new_weights = post_mix_sum / post_sum[..., None]
        m_d = post_mix_sum.copy()
        m_d[(new_weights == 0) & (m_n == 0).all(axis=-1)] = 1.0
        new_mu = m_n / m_d[..., None]
        new_means = new_mu + batch.centre[:, None, None, :]
        c = mu if covariance == "hmmlearn" else new_mu  # the scatter is about c: Σ pcm (x − c)(x − c)ᵀ
        cm = c[..., :, None] * m_n[..., None, :]
        c_n = (
            second
            - cm
            - np.swapaxes(cm, -1, -2)
            + post_mix_sum[..., None, None] * (c[..., :, None] * c[..., None, :])
        )
        if covariance == "ml":
            n = post_mix_sum[..., None, None]
            with np.errstate(divide="ignore", invalid="ignore"):
                new_covars = c_n / n + covar_floor * np.eye(D)
            new_covars = np.where(n > EMPTY, new_covars, covars)
        else:
            new_covars = (covar_reg * np.eye(D) + c_n) / (post_mix_sum + 1.0)[..., None, None]
        for a, new in zip(params, (new_start, new_trans, new_weights, new_means, new_covars), strict=True):
            a[ix] = new
        live = [
            k for k in live if not (len(histories[k]) >= 2 and histories[k][-1] - histories[k][-2] < tols[k])
        ]
        if not live:
            break
    return [FitResult(GMMHMMParams(*(a[k] for a in params)), np.array(histories[k])) for k in range(P)]
