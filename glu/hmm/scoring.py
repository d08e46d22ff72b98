"""Scoring many gesture sequences against every model of a bank: the fast forward passes.

:class:`~glu.hmm.model.GestureHMM` scores one sequence with the readable recursion of
:mod:`glu.hmm.inference`; studies score thousands. Here:

* :func:`stack_models` stacks a bank of models (padded to a common Q and M) into a :class:`Bank`
  (:func:`params_bank` from stacked parameters);
* :func:`loglik_many` gives ``log L(G | model)`` of many sequences under every model of a bank: the
  emissions and the forward recursion run compiled, frame by frame
  (:func:`glu.hmm._engine.kernels.loglik_banked`), each step :func:`~glu.hmm.inference.forward_step`'s;
* :class:`BatchScorer` gives the prefix log-likelihoods ``log L(G_1^t | model)`` of every prefix of many
  sequences (a corpus evaluation scores each at several observed prefixes), vectorised:

1. **Emissions by one matrix product.** Each Gaussian's log-density is a quadratic form in the frame,
   ``log w − ½ (x − μ)ᵀ Σ⁻¹ (x − μ) + const``; expanded over the monomials of the (centred) frame,
   ``φ(x) = (x_i x_j for i ≤ j, x_i, 1)`` (10 terms for D = 3), it is ``φ(x) · c_k`` for a coefficient
   vector ``c_k`` per component. All frames of all sequences times all components of all models
   (A · Q · M columns) is then one matrix product, followed by one exponential per component.
2. **The forward recursion batched** over sequences and models
   (:func:`forward_curves_batch`): one batched ``(S, Q) @ (Q, Q)`` product per frame
   and model, sequences sorted by length so that finished ones drop out.
3. **Exactness kept.** A (model, sequence) pair whose scaled forward mass underflows is recomputed by the
   per-sequence path (:func:`~glu.hmm.inference.forward_curve` with its log-domain fallback), so the
   result equals :meth:`GestureHMM.loglik_curve <glu.hmm.model.GestureHMM.loglik_curve>` for every
   sequence (tested against it and against hmmlearn).

The frames are centred on the mean of the models' means before the expansion, which keeps the
cancellation error of the quadratic form far below the tolerance of the tests (1e-8 relative).

Example
-------
>>> import numpy as np
>>> from glu.hmm.inference import left_to_right_transmat
>>> from glu.hmm.model import GestureHMM
>>> def hmm(shift):
...     return GestureHMM([1.0, 0.0], left_to_right_transmat(2, 0.9), [[1.0], [1.0]],
...                       [[[shift] * 3], [[shift + 1] * 3]], np.tile(np.eye(3), (2, 1, 1, 1)))
>>> scorer = BatchScorer([hmm(0.0), hmm(2.0)])
>>> X = [np.linspace(0, 1, 10)[:, None].repeat(3, axis=1), np.ones((4, 3))]   # two sequences (T, 3)
>>> curves = scorer.loglik_curves(X)                 # (S, T_max, A), NaN after each sequence's end
>>> curves.shape, bool(np.isnan(curves[1, 4:]).all())
((2, 10, 2), True)
>>> bool(np.allclose(curves[0, :, 0], hmm(0.0).loglik_curve(X[0])))
True
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from glu.errors import DataError, ModelError
from glu.hmm._engine.em_batch import quadratic_coefficients as component_coefficients
from glu.hmm._engine.em_batch import quadratic_features
from glu.hmm._engine.kernels import loglik_banked, stream_step
from glu.hmm.em import GMMHMMParams
from glu.hmm.inference import TINY, forward_curve, gaussian_factors, log_emissions
from glu.hmm.model import GestureHMM, as_sequence

PAD_LOG_NORM = -1e300
"""log-normaliser given to the padding components of a stacked bank (never the most likely)."""
EXP_FLOOR = -700.0
"""Scaled component log-densities below this are raised to it before exponentiating (``exp`` is several
times slower on arguments that underflow). It adds at most e⁻⁷⁰⁰ ≈ 1e-304 to a frame's scaled emissions,
whose largest term is 1: below any forward mass the recursion keeps (:data:`~glu.hmm.inference.TINY`,
under which the pair is recomputed exactly)."""
DEFAULT_BATCH = 512
"""Sequences scored together (bounds the memory: T × A × S × Q floats per batch)."""


class Bank(NamedTuple):
    """The models of a recogniser stacked along a leading axis, padded to a common Q and M.

    Attributes
    ----------
    means : array, shape (A, Q, M, D)
    chol_inv : array, shape (A, Q, M, D, D) — inverse Cholesky factors (identity for padding)
    log_norm : array, shape (A, Q, M) — ``log w − (D/2) log 2π − log |L|`` (:data:`PAD_LOG_NORM` for
        padding and for components of weight 0)
    startprob : array, shape (A, Q) (0 for padding states)
    transmat : array, shape (A, Q, Q) (0 rows and columns for padding states)
    """

    means: np.ndarray
    chol_inv: np.ndarray
    log_norm: np.ndarray
    startprob: np.ndarray
    transmat: np.ndarray


def stack_models(models: Sequence[GestureHMM]) -> Bank:
    """Stack ``models`` (same number of features) into one :class:`Bank`, padding Q and M."""
    if not models:
        raise ModelError("a bank needs at least one model")
    dims = {m.n_features for m in models}
    if len(dims) != 1:
        raise ModelError(f"all models must have the same number of features, got {sorted(dims)}")
    A, D = len(models), dims.pop()
    Q = max(m.n_states for m in models)
    M = max(m.n_mix for m in models)
    mu = np.zeros((A, Q, M, D))
    cinv = np.broadcast_to(np.eye(D), (A, Q, M, D, D)).copy()
    lnorm = np.full((A, Q, M), PAD_LOG_NORM)
    pi = np.zeros((A, Q))
    trans = np.zeros((A, Q, Q))
    for i, m in enumerate(models):
        q, k = m.n_states, m.n_mix
        mu[i, :q, :k] = m.means
        cinv[i, :q, :k] = m.chol_inv
        lnorm[i, :q, :k] = np.where(np.isfinite(m.log_norm), m.log_norm, PAD_LOG_NORM)
        pi[i, :q] = m.startprob
        trans[i, :q, :q] = m.transmat
    return Bank(mu, cinv, lnorm, pi, trans)


def params_bank(params: GMMHMMParams) -> Bank:
    """A :class:`Bank` of models given as stacked parameters (:class:`~glu.hmm.em.GMMHMMParams` with one
    leading axis, the models; all of one shape), e.g. the models of online learning."""
    chol_inv, log_norm = gaussian_factors(params.weights, params.covars)
    log_norm = np.where(np.isfinite(log_norm), log_norm, PAD_LOG_NORM)
    return Bank(params.means, chol_inv, log_norm, params.startprob, params.transmat)


def bank_coefficients(bank: Bank) -> tuple[np.ndarray, np.ndarray]:
    """The emission log-densities of every component as coefficients on :func:`quadratic_features`.

    Returns
    -------
    center : array, shape (D,) — the frames are centred on it (the mean of the used means)
    coef : array, shape (D(D+1)/2 + D + 1, A·Q·M) — ``φ(x − center) @ coef`` is
        ``log w_k + log N(x; μ_k, Σ_k)`` for every component k, in (A, Q, M) order
    """
    used = bank.log_norm > PAD_LOG_NORM
    center = bank.means[used].mean(axis=0)
    coef = component_coefficients(bank.means - center, bank.chol_inv, bank.log_norm)  # (A, Q, M, F)
    coef = np.ascontiguousarray(coef.reshape(-1, coef.shape[-1]).T)
    coef[-1] = np.maximum(coef[-1], PAD_LOG_NORM)  # padding components stay hugely negative
    return center, coef


class BatchScorer:
    """Prefix log-likelihoods ``log L(G_1^t | A)`` of many sequences under every model, vectorised.

    Parameters
    ----------
    models : the models, in the order of the output's last axis
        (e.g. ``[rec.models[a] for a in rec.actions]``), or a :class:`~glu.gestures.recognizer.Recognizer`,
        whose invariant features are then computed from each sequence as the recogniser itself does
    batch_size : sequences scored together
    """

    def __init__(self, models: Sequence[GestureHMM] | object, batch_size: int = DEFAULT_BATCH) -> None:
        features = None
        if hasattr(models, "actions") and hasattr(models, "models"):  # a Recognizer: its models and features
            features = getattr(models, "features", None)
            models = [models.models[a] for a in models.actions]
        self.features = None if features is None or features.is_raw else features
        """The recogniser's invariant features (:mod:`glu.gestures.invariants`), computed from every sequence
        before scoring, or None (raw)."""
        self.models: tuple[GestureHMM, ...] = tuple(models)
        self.bank = stack_models(self.models)
        self.n_features = self.bank.means.shape[-1]
        self.center, self.coef = bank_coefficients(self.bank)
        self._coef_t = np.ascontiguousarray(self.coef.T)
        self._trans_t = np.ascontiguousarray(np.swapaxes(self.bank.transmat, -1, -2))
        self.batch_size = int(batch_size)

    @property
    def n_models(self) -> int:
        """A."""
        return len(self.models)

    def loglik_curves(self, sequences: Sequence[np.ndarray]) -> np.ndarray:
        """``log L(G_1^t | model)`` for every prefix of every sequence.

        Parameters
        ----------
        sequences : S arrays of shape (T_s, D), T_s ≥ 1, finite

        Returns
        -------
        array, shape (S, max T_s, A) — entry ``[s, t-1, a]`` is ``log L(G_1^t | model a)`` of sequence s;
        NaN for t > T_s
        """
        seqs = [as_sequence(x, self.n_features, f"sequence {i}") for i, x in enumerate(sequences)]
        if self.features is not None:
            seqs = [self.features.transform(x) for x in seqs]
        lengths = np.array([len(x) for x in seqs], dtype=np.intp)
        out = np.full((len(seqs), int(lengths.max(initial=0)), self.n_models), np.nan)
        order = np.argsort(-lengths, kind="stable")
        for lo in range(0, len(seqs), self.batch_size):
            idx = order[lo : lo + self.batch_size]
            curves = self._score_sorted([seqs[i] for i in idx], lengths[idx])
            for k, i in enumerate(idx):
                out[i, : lengths[i]] = curves[k, : lengths[i]]
        return out

    def loglik_at(self, sequences: Sequence[np.ndarray], ends: np.ndarray) -> np.ndarray:
        """``log L(G_1^t | model)`` at given prefix lengths, shape (S, F, A), for ``ends`` of shape (S, F).

        ``ends[s, f]`` is a number of frames, 1 ≤ ends ≤ T_s.
        """
        ends = np.asarray(ends)
        lengths = np.array([len(x) for x in sequences])
        if ends.ndim != 2 or len(ends) != len(sequences):
            raise DataError(f"ends must have shape (n_sequences={len(sequences)}, n_prefixes)")
        if (ends < 1).any() or (ends > lengths[:, None]).any():
            raise DataError("every prefix length must be between 1 and its sequence's length")
        curves = self.loglik_curves(sequences)
        return np.take_along_axis(curves, (ends - 1)[:, :, None], axis=1)

    def _score_sorted(self, seqs: list[np.ndarray], lengths: np.ndarray) -> np.ndarray:
        """Curves, shape (S, T, A), of sequences sorted by decreasing length."""
        bank = self.bank
        S, T = len(seqs), int(lengths[0])
        A, Q, M = bank.log_norm.shape
        X = np.concatenate(seqs)
        s_of = np.repeat(np.arange(S), lengths)  # frame k of the concatenation is frame t_of of sequence s_of
        t_of = np.arange(len(X)) - np.repeat(np.cumsum(lengths) - lengths, lengths)
        phi = np.zeros((T, self.coef.shape[0], S))  # time-major monomials (padding: zeros)
        phi[t_of, :, s_of] = quadratic_features(X, self.center)
        curves, bad = forward_curves_batch(phi, self._coef_t, lengths, bank.startprob, self._trans_t, M)
        curves = curves.transpose(2, 0, 1)  # (S, T, A)
        for a, s in zip(*np.nonzero(bad), strict=True):  # underflow: the exact per-sequence path
            m = self.models[a]
            lb = log_emissions(seqs[s], m.means, m.chol_inv, m.log_norm)
            curves[s, : lengths[s], a] = forward_curve(lb, m.startprob, m.transmat)
        return curves


def forward_curves_batch(
    phi: np.ndarray,
    coef_t: np.ndarray,
    lengths: np.ndarray,
    startprob: np.ndarray,
    trans_t: np.ndarray,
    n_mix: int,
) -> tuple[np.ndarray, np.ndarray]:
    """The scaled forward recursion of :func:`~glu.hmm.inference.forward_curve`, for S sequences and A
    models at once, computing each frame's emissions on the way.

    At frame t, for the ``n_t`` sequences still running (sequences sorted by decreasing length): the
    component log-densities ``coef_t @ phi[t]`` (one matrix product), scaled by their maximum per model and
    exponentiated, summed over the mixture; then ``alpha ← (transmatᵀ @ alpha) ∘ b``, one batched product
    per model, normalised per (model, sequence). Arrays are laid out (model, state, sequence), so every
    operation runs along the sequences.

    Parameters
    ----------
    phi : array, shape (T, F, S) — :func:`quadratic_features` of frame t of sequence s (any values beyond
        a sequence's end)
    coef_t : array, shape (A·Q·M, F) — the transpose of :func:`bank_coefficients`' ``coef``
    lengths : int array, shape (S,) — non-increasing, each between 1 and T
    startprob : array, shape (A, Q)
    trans_t : array, shape (A, Q, Q) — transition matrices transposed, ``trans_t[a, j, i] = P(i → j)``
    n_mix : M

    Returns
    -------
    curves : array, shape (T, A, S) — ``log L(G_1^t)`` (undefined beyond a sequence's end)
    bad : bool array, shape (A, S) — pairs whose scaled forward mass fell to :data:`~glu.hmm.inference.TINY`
        or below at some frame (underflow, or an impossible frame): recompute those exactly
    """
    T, _, S = phi.shape
    A, Q = startprob.shape
    active = (np.asarray(lengths)[None, :] > np.arange(T)[:, None]).sum(axis=1)
    curves = np.zeros((T, A, S))
    bad = np.zeros((A, S), dtype=bool)
    loglik = np.zeros((A, S))
    alpha = np.zeros((A, Q, S))
    for t in range(T):
        n = int(active[t])
        comp = (coef_t @ phi[t, :, :n]).reshape(A, Q * n_mix, n)
        scale = comp.max(axis=1)  # per model and sequence
        np.subtract(comp, scale[:, None, :], out=comp)
        np.maximum(comp, EXP_FLOOR, out=comp)  # exp's fast path; see EXP_FLOOR
        np.exp(comp, out=comp)
        b = comp.reshape(A, Q, n_mix, n).sum(axis=2)  # (A, Q, n)
        if t == 0:
            a = startprob[:, :, None] * b
        else:
            a = np.matmul(trans_t, alpha[:, :, :n])
            a *= b
        c = a.sum(axis=1)  # (A, n)
        low = c <= TINY
        if low.any():
            bad[:, :n] |= low
            c[low] = 1.0
        a /= c[:, None, :]
        alpha[:, :, :n] = a
        loglik[:, :n] += np.log(c) + scale
        curves[t, :, :n] = loglik[:, :n]
    return curves, bad


def loglik_many(bank: Bank, sequences: Sequence[np.ndarray]) -> np.ndarray:
    """``log L(G | model)`` of many sequences under every model of a bank, shape (S, n_models), in one batch.

    The emissions and the forward recursion run compiled, frame by frame
    (:func:`glu.hmm._engine.kernels.loglik_banked`), each step :func:`~glu.hmm.inference.forward_step`'s
    (including its log-domain fallback where the scaled mass underflows): the last entry of
    ``forward_curve`` for each sequence, to rounding (1e-12 relative,
    ``tests/studies/test_batched_experiments.py``).

    Parameters
    ----------
    bank : the stacked models (:func:`stack_models`)
    sequences : the feature sequences the models see, each of shape (T_i, D)

    Examples
    --------
    >>> from glu.hmm.inference import left_to_right_transmat
    >>> hmm = GestureHMM([1.0, 0.0], left_to_right_transmat(2, 0.9), [[1.0], [1.0]],
    ...                  [[[0.0] * 3], [[1.0] * 3]], np.tile(np.eye(3), (2, 1, 1, 1)))
    >>> X = np.linspace(0, 1, 10)[:, None].repeat(3, axis=1)
    >>> bool(np.isclose(loglik_many(stack_models([hmm, hmm]), [X])[0, 1], hmm.loglik(X)))
    True
    """
    seqs = list(sequences)
    if not seqs:
        return np.empty((0, len(bank.startprob)))
    return loglik_banked(seqs, bank.means, bank.chol_inv, bank.log_norm, bank.startprob, bank.transmat)


class BankStream:
    """Every model of a bank advanced one frame at a time: :func:`loglik_many`'s compiled recursion with
    its state kept between frames, so that frame t costs the same whatever came before and the
    log-likelihoods after frame t are those of :func:`loglik_many` on the first t frames (the same
    arithmetic in the same order).

    Attributes
    ----------
    t : frames pushed since the last :meth:`reset`
    loglik : ``log L(G_1^t | model)`` of each model, shape (n_models,) (updated in place by :meth:`push`)
    """

    def __init__(self, bank: Bank) -> None:
        self._bank = tuple(np.ascontiguousarray(a, dtype=np.float64) for a in bank)  # in Bank's field order
        self._alpha = np.zeros(bank.startprob.shape)
        self.loglik = np.zeros(len(bank.startprob))
        self.t = 0

    def reset(self) -> None:
        """Forget every frame."""
        self._alpha[:] = 0.0
        self.loglik[:] = 0.0
        self.t = 0

    def push(self, x: np.ndarray) -> np.ndarray:
        """Advance by one frame ``x`` (float64, shape (D,), C-ordered); returns :attr:`loglik`."""
        stream_step(x, self.t == 0, self._alpha, self.loglik, *self._bank)
        self.t += 1
        return self.loglik
