"""Gesture HMMs: one left-to-right GMM-HMM per action, the recogniser over the bank, streaming posteriors.

The model of METHOD.md §1: for each action ``a`` a left-to-right HMM with ``Q`` states whose emissions
are mixtures of ``M`` full-covariance Gaussians over the 3-D hand features (:mod:`glu.features`).
The forward algorithm gives ``log L(G_1^T | A=a)``; with equal priors the posterior is
``p_HMM(a | G) = L(G|a) / Σ_h L(G|h)``, computed in the log domain.

* :class:`GestureHMM` holds one model's parameters (immutable) and scores sequences: emission
  log-densities are computed once per sequence with precomputed Cholesky factors, then the forward
  recursion runs over a ``(T, Q)`` array (:func:`forward_curve`), which also yields every prefix
  log-likelihood ``log L(G_1^t | a)`` in the same pass.
* :class:`Recognizer` is the bank: :meth:`~Recognizer.loglik`, :meth:`~Recognizer.p_hmm`, the curves over
  prefixes, and :meth:`~Recognizer.stream`, a :class:`GestureStream` that consumes one frame at a time at
  O(1) cost per frame (incremental forward recursion over all models at once).
* :func:`train_hmm` / :func:`train_recognizer` fit the models with hmmlearn's ``GMMHMM``: left-to-right
  structure (zero transitions stay zero under EM), initialised from equal time slices of each training
  sequence, explicit ``n_iter`` and ``tol``, convergence checked and reported
  (:class:`TrainingReport`; hmmlearn itself only logs non-convergence, and counts reaching ``n_iter``
  as converged).
* :func:`load_original_models` imports the 2013 models of the originals from their ``.mat`` files.

Recogniser files (:meth:`Recognizer.save`) are JSON, not pickle::

    {"format": "glu-gesture-recognizer", "version": 1,
     "features": "<what the models expect>",
     "actions": ["grasp", "tap", "touch"],
     "models": {"grasp": {"n_states": Q, "n_mix": M, "n_features": D,
                          "startprob": [Q], "transmat": [Q][Q], "weights": [Q][M],
                          "means": [Q][M][D], "covars": [Q][M][D][D]}, …},
     "training": {"grasp": {<TrainingReport fields>}, …},
     "meta": {<free-form: data source, seed, parameters>}}

Floats are written with ``repr`` precision, so a saved recogniser scores exactly as the one in memory.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from glu.errors import DataError, ModelError
from glu.schema import AFFORDANCE_VALUES

ACTIONS: tuple[str, ...] = AFFORDANCE_VALUES["Action"]
"""The BN's Action values, in the BN's order: grasp, tap, touch."""

ORIGINAL_MODEL_INDEX: dict[str, int] = {"grasp": 3, "tap": 1, "touch": 4, "garbage": 0}
"""Variable index k of ``hmm{k}_*`` in the original .mat files. There was no touch model: the originals
used the push model (k = 4) in its place (METHOD.md §4)."""

ORIGINAL_MODEL_FILES: dict[int, str] = {
    3: "reference-models/HMM_M3_Q6_mixsplit.mat",
    1: "reference-models/HMM_M1_Q6_mixsplit.mat",
}
"""Mixture components M → the original model file, relative to a data folder."""

FEATURES_DESCRIPTION = (
    "right hand minus torso; x (right) and z (back) / mean shoulder distance, y (up) / mean neck-torso "
    "distance (METHOD.md §4); YARP hand logs / 1000"
)
FORMAT = "glu-gesture-recognizer"
FORMAT_VERSION = 1
N_STATES, N_MIX = 6, 3
N_ITER, TOL = 200, 1e-4
COVAR_REG = 1e-3
_TINY = 1e-280
_LOG_2PI = math.log(2 * math.pi)
_PAD = -1e300


class HMMConvergenceWarning(UserWarning):
    """EM stopped without converging (iteration limit reached, or the log-likelihood decreased)."""


# --------------------------------------------------------------------------------------------------
# the forward recursion (pure functions)


def forward_curve(log_b: np.ndarray, startprob: np.ndarray, transmat: np.ndarray) -> np.ndarray:
    """Prefix log-likelihoods ``log L(G_1^t)`` for t = 1 … T by the forward algorithm.

    Parameters
    ----------
    log_b : array, shape (T, Q) — emission log-densities ``log p(g_t | state q)``
    startprob : array, shape (Q,)
    transmat : array, shape (Q, Q) — ``transmat[i, j] = P(q_{t+1} = j | q_t = i)``

    Returns
    -------
    array, shape (T,) — entry t-1 is ``log L(G_1^t)``; the last is the sequence's log-likelihood.

    The recursion is scaled (normalised forward variables, frame-wise maximum of ``log_b`` factored out);
    a frame whose scaled emissions underflow for every reachable state is redone in the log domain.
    """
    T, Q = log_b.shape
    out = np.empty(T)
    if T == 0:
        return out
    mx = log_b.max(axis=1)
    eb = np.exp(log_b - mx[:, None])
    alpha = startprob  # normalised forward variables of the previous frame
    total = 0.0
    for t in range(T):
        new = startprob * eb[0] if t == 0 else (alpha @ transmat) * eb[t]
        c = new.sum()
        if not c > _TINY:  # underflow (or an impossible frame): redo this frame in the log domain
            with np.errstate(divide="ignore"):
                la = np.log(startprob if t == 0 else alpha @ transmat) + log_b[t]
            m = la.max()
            if not np.isfinite(m):
                out[t:] = -np.inf
                return out
            new = np.exp(la - m)
            c = new.sum()
            total += m + math.log(c)
        else:
            total += math.log(c) + mx[t]
        alpha = new / c
        out[t] = total
    return out


def log_softmax(loglik: np.ndarray) -> np.ndarray:
    """``log p(a) = loglik[..., a] - logsumexp(loglik[..., :])`` (equal priors), shape as ``loglik``."""
    loglik = np.asarray(loglik, dtype=float)
    m = loglik.max(axis=-1, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore"):
        return loglik - (np.log(np.exp(loglik - m).sum(axis=-1, keepdims=True)) + m)


def p_hmm_from_loglik(loglik: np.ndarray) -> np.ndarray:
    """The posterior ``p_HMM(A | G)`` with equal priors from log-likelihoods, shape (..., n_actions)."""
    return np.exp(log_softmax(loglik))


def left_to_right_transmat(n_states: int, stay: float) -> np.ndarray:
    """A left-to-right transition matrix, shape (Q, Q): stay with ``stay``, else move one state right."""
    A = np.zeros((n_states, n_states))
    for q in range(n_states - 1):
        A[q, q], A[q, q + 1] = stay, 1.0 - stay
    A[-1, -1] = 1.0
    return A


# --------------------------------------------------------------------------------------------------
# one model


def _as_sequence(X: Any, n_features: int, what: str = "sequence") -> np.ndarray:
    try:
        X = np.asarray(X, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"{what}: not an array of numbers") from None
    if X.ndim != 2 or X.shape[1] != n_features:
        raise DataError(f"{what}: expected shape (n_frames, {n_features}), got {X.shape}")
    if len(X) == 0:
        raise DataError(f"{what}: no frames")
    if not np.all(np.isfinite(X)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(X), axis=1))[0])
        raise DataError(f"{what}: frame {bad + 1} (1-based) is not finite")
    return X


@dataclass(frozen=True, eq=False)
class GestureHMM:
    """A left-to-right HMM with Gaussian-mixture emissions (parameters only; immutable).

    Attributes
    ----------
    startprob : array, shape (Q,)
    transmat : array, shape (Q, Q), rows sum to one
    weights : array, shape (Q, M), mixture weights, rows sum to one
    means : array, shape (Q, M, D)
    covars : array, shape (Q, M, D, D), full covariances (positive definite where the weight is > 0)
    name : the action it models
    """

    startprob: np.ndarray
    transmat: np.ndarray
    weights: np.ndarray
    means: np.ndarray
    covars: np.ndarray
    name: str = ""
    _chol_inv: np.ndarray = field(init=False, repr=False)
    _log_norm: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        who = f"HMM {self.name!r}" if self.name else "HMM"
        arrs = {}
        for k in ("startprob", "transmat", "weights", "means", "covars"):
            try:
                a = np.array(getattr(self, k), dtype=float)
            except (TypeError, ValueError):
                raise ModelError(f"{who}: {k} is not an array of numbers") from None
            if not np.all(np.isfinite(a)):
                raise ModelError(f"{who}: {k} has non-finite values")
            arrs[k] = a
        if arrs["means"].ndim != 3:
            raise ModelError(f"{who}: means must have shape (Q, M, D), got {arrs['means'].shape}")
        Q, M, D = arrs["means"].shape
        shapes = {"startprob": (Q,), "transmat": (Q, Q), "weights": (Q, M), "covars": (Q, M, D, D)}
        for k, s in shapes.items():
            if arrs[k].shape != s:
                raise ModelError(f"{who}: {k} must have shape {s} (Q={Q}, M={M}, D={D}), got {arrs[k].shape}")
        for k, axis in (("startprob", 0), ("transmat", 1), ("weights", 1)):
            a = arrs[k]
            if np.any(a < 0) or not np.allclose(a.sum(axis=axis), 1.0, rtol=0, atol=1e-6):
                raise ModelError(f"{who}: {k} must be non-negative and sum to one (along axis {axis})")
        cov = arrs["covars"]
        if not np.allclose(cov, np.swapaxes(cov, -1, -2), rtol=1e-8, atol=1e-12):
            raise ModelError(f"{who}: covariances must be symmetric")
        used = arrs["weights"] > 0
        safe = np.where(used[..., None, None], cov, np.eye(D))
        try:
            L = np.linalg.cholesky(safe)
        except np.linalg.LinAlgError:
            raise ModelError(f"{who}: a covariance matrix is not positive definite") from None
        chol_inv = np.linalg.inv(L)
        with np.errstate(divide="ignore"):
            log_norm = (
                np.log(arrs["weights"])
                - 0.5 * D * _LOG_2PI
                - np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(axis=-1)
            )
        for k, a in arrs.items():
            a.flags.writeable = False
            object.__setattr__(self, k, a)
        object.__setattr__(self, "_chol_inv", chol_inv)
        object.__setattr__(self, "_log_norm", log_norm)

    @property
    def n_states(self) -> int:
        """Q."""
        return self.means.shape[0]

    @property
    def n_mix(self) -> int:
        """M."""
        return self.means.shape[1]

    @property
    def n_features(self) -> int:
        """D."""
        return self.means.shape[2]

    @property
    def is_left_to_right(self) -> bool:
        """True if no transition goes to an earlier state (transmat is upper triangular)."""
        return bool(np.all(np.tril(self.transmat, -1) == 0))

    def log_emission(self, X: np.ndarray) -> np.ndarray:
        """Emission log-densities ``log p(x_t | q)``, shape (T, Q), for a sequence of shape (T, D)."""
        X = _as_sequence(X, self.n_features)
        diff = X[:, None, None, :] - self.means[None]  # (T, Q, M, D)
        z = np.einsum("qmij,tqmj->tqmi", self._chol_inv, diff, optimize=False)
        lc = self._log_norm[None] - 0.5 * np.einsum("tqmi,tqmi->tqm", z, z)
        m = lc.max(axis=2)
        return np.log(np.exp(lc - m[..., None]).sum(axis=2)) + m

    def loglik_curve(self, X: np.ndarray) -> np.ndarray:
        """``log L(G_1^t | model)`` for every prefix t = 1 … T, shape (T,), of a sequence of shape (T, D)."""
        return forward_curve(self.log_emission(X), self.startprob, self.transmat)

    def loglik(self, X: np.ndarray) -> float:
        """``log L(G | model)`` of a sequence of shape (T, D), by the forward algorithm."""
        return float(self.loglik_curve(X)[-1])

    def to_dict(self) -> dict[str, Any]:
        """The parameters as nested lists (the ``models`` entries of the recogniser file)."""
        return {
            "n_states": self.n_states, "n_mix": self.n_mix, "n_features": self.n_features,
            "startprob": self.startprob.tolist(), "transmat": self.transmat.tolist(),
            "weights": self.weights.tolist(), "means": self.means.tolist(), "covars": self.covars.tolist(),
        }  # fmt: skip

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], name: str = "") -> GestureHMM:
        """A model from :meth:`to_dict` output; raises :class:`ModelError` if malformed."""
        try:
            return cls(d["startprob"], d["transmat"], d["weights"], d["means"], d["covars"], name=name)
        except (KeyError, TypeError) as e:
            raise ModelError(f"HMM {name!r}: missing or malformed field {e}") from None

    def to_hmmlearn(self) -> Any:
        """An equivalent ``hmmlearn.hmm.GMMHMM`` (for cross-checks)."""
        from hmmlearn.hmm import GMMHMM

        m = GMMHMM(n_components=self.n_states, n_mix=self.n_mix, covariance_type="full", init_params="")
        m.n_features = self.n_features
        m.startprob_, m.transmat_ = self.startprob.copy(), self.transmat.copy()
        m.weights_, m.means_, m.covars_ = self.weights.copy(), self.means.copy(), self.covars.copy()
        return m

    @classmethod
    def from_hmmlearn(cls, model: Any, name: str = "") -> GestureHMM:
        """The parameters of a fitted full-covariance ``GMMHMM``."""
        return cls(model.startprob_, model.transmat_, model.weights_, model.means_, model.covars_, name=name)


# --------------------------------------------------------------------------------------------------
# training


@dataclass(frozen=True)
class TrainingReport:
    """How EM went for one model.

    Attributes
    ----------
    action : the model's action
    n_sequences, n_frames : the training data
    n_iter : EM iterations run (of at most ``max_iter``)
    converged : True if the last change of the total log-likelihood, per training frame, was smaller
        than ``tol`` in absolute value (a gain below ``tol``, not a larger decrease)
    history : total training log-likelihood before each M-step
    final_loglik : total training log-likelihood of the returned model
    tol : the tolerance, in log-likelihood per training frame
    max_iter : the iteration limit
    """

    action: str
    n_sequences: int
    n_frames: int
    n_iter: int
    converged: bool
    history: tuple[float, ...]
    final_loglik: float
    tol: float
    max_iter: int

    def describe(self) -> str:
        """One line, e.g. ``grasp: 40 sequences, 3812 frames; converged after 17 EM iterations …``."""
        delta = self.history[-1] - self.history[-2] if len(self.history) >= 2 else float("nan")
        state = (
            f"converged after {self.n_iter} EM iterations (last gain {delta:.3g} < tol "
            f"{self.tol:g} × {self.n_frames} frames)"
            if self.converged
            else f"NOT converged after {self.n_iter} of {self.max_iter} EM iterations "
            f"(last change {delta:.3g}, tol {self.tol:g} × {self.n_frames} frames)"
        )
        return (
            f"{self.action}: {self.n_sequences} sequences, {self.n_frames} frames; {state}; "
            f"log L = {self.final_loglik:.2f} ({self.final_loglik / max(self.n_frames, 1):.3f} per frame)"
        )


def init_left_to_right(
    sequences: Sequence[np.ndarray],
    n_states: int = N_STATES,
    n_mix: int = N_MIX,
    seed: int = 0,
    covar_reg: float = COVAR_REG,
    name: str = "",
) -> GestureHMM:
    """An initial left-to-right model: each sequence cut into ``n_states`` equal time slices, slice q → state q.

    The frames of slice q (over all sequences) give state q's mixture (scikit-learn ``GaussianMixture``,
    seeded; with too few frames, one Gaussian copied ``n_mix`` times with means spread along its main
    axis). Self-transition probabilities are ``1 - 1 / (mean frames per state)``, clipped to [0.5, 0.98].
    ``sequences`` are arrays of shape (T_i, D).
    """
    from sklearn.mixture import GaussianMixture

    D = sequences[0].shape[1]
    slices: list[list[np.ndarray]] = [[] for _ in range(n_states)]
    for X in sequences:
        idx = np.minimum((np.arange(len(X)) * n_states) // len(X), n_states - 1)
        for q in range(n_states):
            slices[q].append(X[idx == q])
    weights = np.zeros((n_states, n_mix))
    means = np.zeros((n_states, n_mix, D))
    covars = np.zeros((n_states, n_mix, D, D))
    pooled_all = np.concatenate(sequences)
    for q in range(n_states):
        Xq = np.concatenate(slices[q]) if any(len(s) for s in slices[q]) else pooled_all
        if len(Xq) >= max(4 * n_mix * D, n_mix + 1) and len(np.unique(Xq, axis=0)) > n_mix:
            gm = GaussianMixture(
                n_mix, covariance_type="full", reg_covar=covar_reg, random_state=seed, n_init=1
            )
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                gm.fit(Xq)
            weights[q], means[q], covars[q] = gm.weights_, gm.means_, gm.covariances_
        else:
            mu = Xq.mean(axis=0)
            cov = (np.cov(Xq.T) if len(Xq) > 1 else np.zeros((D, D))).reshape(D, D) + covar_reg * np.eye(D)
            w, v = np.linalg.eigh(cov)
            spread = np.linspace(-0.5, 0.5, n_mix) if n_mix > 1 else np.zeros(1)
            weights[q] = 1.0 / n_mix
            means[q] = mu + spread[:, None] * math.sqrt(w[-1]) * v[:, -1]
            covars[q] = cov
    covars = 0.5 * (covars + np.swapaxes(covars, -1, -2))
    mean_len = float(np.mean([len(X) for X in sequences]))
    stay = float(np.clip(1.0 - n_states / mean_len, 0.5, 0.98))
    startprob = np.zeros(n_states)
    startprob[0] = 1.0
    return GestureHMM(startprob, left_to_right_transmat(n_states, stay), weights, means, covars, name=name)


def _preset_gmmhmm_class() -> type:
    from hmmlearn.hmm import GMMHMM

    class PresetGMMHMM(GMMHMM):
        """GMMHMM whose parameters are all given before ``fit`` (skips hmmlearn's k-means initialisation)."""

        def _init(self, X, lengths=None):  # type: ignore[no-untyped-def]
            if not hasattr(self, "_check_and_set_n_features"):  # pragma: no cover - other hmmlearn versions
                return super()._init(X, lengths)
            self._check_and_set_n_features(X)
            self._init_covar_priors()
            self._fix_priors_shape()

    return PresetGMMHMM


def train_hmm(
    sequences: Sequence[np.ndarray],
    n_states: int = N_STATES,
    n_mix: int = N_MIX,
    *,
    n_iter: int = N_ITER,
    tol: float = TOL,
    covar_reg: float = COVAR_REG,
    seed: int = 0,
    name: str = "",
    warn: bool = True,
) -> tuple[GestureHMM, TrainingReport]:
    """Fit a left-to-right GMM-HMM to sequences of shape (T_i, D) with hmmlearn's EM (Baum–Welch).

    Parameters
    ----------
    sequences : the training sequences, each an array of shape (T_i, D)
    n_states, n_mix : Q and M
    n_iter, tol : at most ``n_iter`` EM iterations; converged when the total log-likelihood gains less
        than ``tol`` × the number of training frames in an iteration (``tol`` is per frame, so it means
        the same for any amount of data; hmmlearn's own ``tol`` is this product)
    covar_reg : each covariance gets a weak inverse-Wishart prior, ``Σ = (S + covar_reg·I) / (N + 1)``
        for scatter S and soft count N, so a component with few frames cannot collapse
    seed : seeds the initial mixtures
    name : the action (for messages)
    warn : emit an :class:`HMMConvergenceWarning` when EM does not converge

    Returns
    -------
    the model and a :class:`TrainingReport`. Zero transitions of the left-to-right initialisation stay
    zero (EM cannot create transitions that have zero probability).
    """
    who = f"training data for {name!r}" if name else "training data"
    if len(sequences) == 0:
        raise DataError(f"{who}: no sequences")
    D = np.asarray(sequences[0]).shape[-1] if np.asarray(sequences[0]).ndim == 2 else 3
    seqs = [_as_sequence(X, D, f"{who}, sequence {i + 1}") for i, X in enumerate(sequences)]
    n_frames = sum(len(X) for X in seqs)
    if n_states < 1 or n_mix < 1:
        raise ModelError(f"n_states={n_states} and n_mix={n_mix} must be ≥ 1")
    if n_frames < n_states * n_mix:
        raise DataError(f"{who}: {n_frames} frames are too few for {n_states} states × {n_mix} mixtures")
    if n_iter < 1 or not tol > 0:
        raise ModelError(f"n_iter={n_iter} must be ≥ 1 and tol={tol} > 0")
    init = init_left_to_right(seqs, n_states, n_mix, seed, covar_reg, name)
    model = _preset_gmmhmm_class()(
        n_components=n_states, n_mix=n_mix, covariance_type="full", n_iter=n_iter, tol=tol * n_frames,
        params="stmcw", init_params="", random_state=seed, implementation="log",
        covars_prior=covar_reg * np.eye(D), covars_weight=-(D + 1.0),
    )  # fmt: skip
    model.startprob_, model.transmat_ = init.startprob.copy(), init.transmat.copy()
    model.weights_, model.means_, model.covars_ = init.weights.copy(), init.means.copy(), init.covars.copy()
    import logging

    hmm_log = logging.getLogger("hmmlearn.base")
    level = hmm_log.level
    hmm_log.setLevel(logging.ERROR)  # we report non-convergence ourselves
    from threadpoolctl import threadpool_limits

    try:
        # one BLAS thread: hmmlearn's many tiny solves are several times slower with thread hand-offs
        with warnings.catch_warnings(), np.errstate(all="ignore"), threadpool_limits(1):
            warnings.simplefilter("ignore", RuntimeWarning)
            model.fit(np.concatenate(seqs), [len(X) for X in seqs])
    except (ValueError, np.linalg.LinAlgError) as e:
        raise ModelError(f"EM failed for {name or 'the model'}: {e}") from None
    finally:
        hmm_log.setLevel(level)
    try:
        fitted = GestureHMM.from_hmmlearn(model, name=name)
    except ModelError as e:
        raise ModelError(f"EM diverged for {name or 'the model'} ({e}); try a larger covar_reg") from None
    history = tuple(float(h) for h in model.monitor_.history)
    delta = history[-1] - history[-2] if len(history) >= 2 else math.inf
    converged = bool(abs(delta) < tol * n_frames)
    final = float(sum(fitted.loglik(X) for X in seqs))
    report = TrainingReport(name, len(seqs), n_frames, len(history), converged, history, final, tol, n_iter)
    if not converged and warn:
        warnings.warn(report.describe(), HMMConvergenceWarning, stacklevel=2)
    return fitted, report


# --------------------------------------------------------------------------------------------------
# the recogniser bank and its streaming form


class StreamStep(NamedTuple):
    """One step of a :class:`GestureStream`.

    Attributes
    ----------
    t : frames consumed so far (1-based index of the frame just pushed)
    loglik : array, shape (n_actions,) — ``log L(G_1^t | A)``
    p_hmm : array, shape (n_actions,) — ``p_HMM(A | G_1^t)`` (equal priors)
    """

    t: int
    loglik: np.ndarray
    p_hmm: np.ndarray


class GestureStream:
    """Incremental forward recursion over every model of a recogniser: one frame in, one posterior out.

    Each :meth:`push` costs O(Σ_a Q_a² + Σ_a Q_a M_a D²), independent of how many frames came before;
    the results equal rescoring the prefix ``G_1^t`` from scratch. Models are stacked (padded to the
    largest Q and M) so one step is a handful of array operations.
    """

    def __init__(self, recognizer: Recognizer) -> None:
        models = [recognizer.models[a] for a in recognizer.actions]
        self.actions: tuple[str, ...] = recognizer.actions
        A = len(models)
        Q = max(m.n_states for m in models)
        M = max(m.n_mix for m in models)
        D = models[0].n_features
        mu = np.zeros((A, Q, M, D))
        cinv = np.broadcast_to(np.eye(D), (A, Q, M, D, D)).copy()
        lnorm = np.full((A, Q, M), _PAD)
        log_pi = np.full((A, Q), -np.inf)
        trans = np.zeros((A, Q, Q))
        for i, m in enumerate(models):
            q, k = m.n_states, m.n_mix
            mu[i, :q, :k] = m.means
            cinv[i, :q, :k] = m._chol_inv
            lnorm[i, :q, :k] = m._log_norm
            with np.errstate(divide="ignore"):
                log_pi[i, :q] = np.log(m.startprob)
            trans[i, :q, :q] = m.transmat
        self._shape = (A, Q, M)
        self._D = D
        self._mu = mu.reshape(-1, D)
        self._cinv = cinv.reshape(-1, D, D)
        self._lnorm = np.where(np.isfinite(lnorm), lnorm, _PAD).reshape(-1)
        self._log_pi = log_pi
        self._trans = trans
        self.reset()

    def reset(self) -> None:
        """Forget every frame: the next :meth:`push` starts a new gesture."""
        self._la: np.ndarray | None = None
        self.t = 0

    def _log_b(self, x: np.ndarray) -> np.ndarray:
        A, Q, M = self._shape
        diff = x - self._mu  # (K, D)
        z = np.matmul(self._cinv, diff[:, :, None])[:, :, 0]
        lc = (self._lnorm - 0.5 * np.einsum("ki,ki->k", z, z)).reshape(A * Q, M)
        mx = lc.max(axis=1)
        return (np.log(np.exp(lc - mx[:, None]).sum(axis=1)) + mx).reshape(A, Q)

    def push(self, x: np.ndarray) -> StreamStep:
        """Consume one frame, shape (D,); return ``log L(G_1^t | A)`` and ``p_HMM(A | G_1^t)``."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self._D,) or not np.all(np.isfinite(x)):
            raise DataError(f"a frame must be {self._D} finite numbers, got {x!r}")
        lb = self._log_b(x)
        if self._la is None:
            la = self._log_pi + lb
        else:
            m = self._la.max(axis=1, keepdims=True)
            p = np.exp(self._la - m)
            with np.errstate(divide="ignore"):
                la = np.log(np.matmul(p[:, None, :], self._trans)[:, 0, :]) + (m + lb)
        self._la = la
        self.t += 1
        m2 = la.max(axis=1)
        ll = np.log(np.exp(la - m2[:, None]).sum(axis=1)) + m2
        return StreamStep(self.t, ll, p_hmm_from_loglik(ll))

    def extend(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Push every frame of X, shape (T, D); return loglik and p_hmm per frame, each shape (T, n_actions)."""
        X = _as_sequence(X, self._D)
        ll = np.empty((len(X), len(self.actions)))
        for t, x in enumerate(X):
            ll[t] = self.push(x).loglik
        return ll, p_hmm_from_loglik(ll)


class Recognizer:
    """A bank of gesture HMMs, one per action: log-likelihoods, posteriors ``p_HMM(A | G)``, streaming.

    Parameters
    ----------
    models : action → :class:`GestureHMM` (the order is the order of every output vector)
    reports : action → :class:`TrainingReport`, if trained by glu
    meta : free-form information saved with the recogniser (data source, seed, parameters)
    """

    def __init__(
        self,
        models: Mapping[str, GestureHMM],
        reports: Mapping[str, TrainingReport] | None = None,
        meta: Mapping[str, Any] | None = None,
    ) -> None:
        if not models:
            raise ModelError("a recogniser needs at least one model")
        dims = {m.n_features for m in models.values()}
        if len(dims) != 1:
            raise ModelError(f"all models must have the same number of features, got {sorted(dims)}")
        self.models: dict[str, GestureHMM] = dict(models)
        self.actions: tuple[str, ...] = tuple(models)
        self.reports: dict[str, TrainingReport] = dict(reports or {})
        self.meta: dict[str, Any] = dict(meta or {})
        self.n_features: int = dims.pop()

    def __repr__(self) -> str:
        shapes = ", ".join(f"{a}: Q={m.n_states} M={m.n_mix}" for a, m in self.models.items())
        return f"Recognizer({shapes})"

    def loglik(self, X: np.ndarray) -> np.ndarray:
        """``log L(G | A)`` for each action, shape (n_actions,), of a sequence of shape (T, D)."""
        X = _as_sequence(X, self.n_features)
        return np.array([self.models[a].loglik(X) for a in self.actions])

    def p_hmm(self, X: np.ndarray) -> np.ndarray:
        """``p_HMM(A | G)`` with equal priors, shape (n_actions,), of a sequence of shape (T, D)."""
        return p_hmm_from_loglik(self.loglik(X))

    def loglik_curve(self, X: np.ndarray) -> np.ndarray:
        """``log L(G_1^t | A)`` for every prefix, shape (T, n_actions)."""
        X = _as_sequence(X, self.n_features)
        return np.stack([self.models[a].loglik_curve(X) for a in self.actions], axis=1)

    def p_hmm_curve(self, X: np.ndarray) -> np.ndarray:
        """``p_HMM(A | G_1^t)`` for every prefix, shape (T, n_actions)."""
        return p_hmm_from_loglik(self.loglik_curve(X))

    def classify(self, X: np.ndarray) -> str:
        """The action with the highest likelihood."""
        return self.actions[int(np.argmax(self.loglik(X)))]

    def stream(self) -> GestureStream:
        """A fresh :class:`GestureStream` over this bank."""
        return GestureStream(self)

    # ------------------------------------------------------------------ files

    def to_dict(self) -> dict[str, Any]:
        """The recogniser file's content (see the module docstring)."""
        return {
            "format": FORMAT,
            "version": FORMAT_VERSION,
            "features": FEATURES_DESCRIPTION,
            "actions": list(self.actions),
            "models": {a: self.models[a].to_dict() for a in self.actions},
            "training": {a: asdict(r) for a, r in self.reports.items()},
            "meta": self.meta,
        }

    @classmethod
    def from_dict(cls, d: Any, source: str = "<dict>") -> Recognizer:
        """A recogniser from :meth:`to_dict` output; :class:`ModelError` naming ``source`` if malformed."""
        if not isinstance(d, dict) or d.get("format") != FORMAT:
            raise ModelError(f'{source}: not a glu gesture recogniser (expected "format": "{FORMAT}")')
        if d.get("version") != FORMAT_VERSION:
            raise ModelError(
                f"{source}: format version {d.get('version')!r}; this glu reads {FORMAT_VERSION}"
            )
        actions, models = d.get("actions"), d.get("models")
        if not isinstance(actions, list) or not isinstance(models, dict) or set(actions) != set(models):
            raise ModelError(f"{source}: 'actions' must list exactly the keys of 'models'")
        try:
            hmms = {a: GestureHMM.from_dict(models[a], name=a) for a in actions}
        except ModelError as e:
            raise ModelError(f"{source}: {e}") from None
        reports = {}
        for a, r in (d.get("training") or {}).items():
            try:
                reports[a] = TrainingReport(**{**r, "history": tuple(r["history"])})
            except (TypeError, KeyError):
                raise ModelError(f"{source}: malformed training report for {a!r}") from None
        return cls(hmms, reports, d.get("meta") or {})

    def save(self, path: str | os.PathLike) -> Path:
        """Write the recogniser as JSON (atomically); returns the path."""
        from glu.data.tables import atomic_write_text

        path = Path(path)
        atomic_write_text(path, json.dumps(self.to_dict(), indent=1, allow_nan=True) + "\n")
        return path

    @classmethod
    def load(cls, path: str | os.PathLike) -> Recognizer:
        """Read a recogniser written by :meth:`save`; :class:`ModelError` if the file is not one."""
        path = Path(path)
        try:
            d = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ModelError(f"{path}: no such recogniser file") from None
        except IsADirectoryError:
            raise ModelError(f"{path}: is a folder, not a recogniser file") from None
        except (UnicodeDecodeError, json.JSONDecodeError) as e:
            raise ModelError(f"{path}: not a JSON recogniser file ({e})") from None
        return cls.from_dict(d, str(path))


def train_recognizer(
    sequences: Mapping[str, Sequence[np.ndarray]],
    n_states: int = N_STATES,
    n_mix: int = N_MIX,
    *,
    n_iter: int = N_ITER,
    tol: float = TOL,
    covar_reg: float = COVAR_REG,
    seed: int = 0,
    warn: bool = True,
    meta: Mapping[str, Any] | None = None,
) -> Recognizer:
    """Train one left-to-right GMM-HMM per action (see :func:`train_hmm`); ``sequences``: action → list of (T_i, D)."""
    models, reports = {}, {}
    for action, seqs in sequences.items():
        models[action], reports[action] = train_hmm(
            seqs,
            n_states,
            n_mix,
            n_iter=n_iter,
            tol=tol,
            covar_reg=covar_reg,
            seed=seed,
            name=action,
            warn=warn,
        )
    info = {
        "n_states": n_states,
        "n_mix": n_mix,
        "n_iter": n_iter,
        "tol": tol,
        "covar_reg": covar_reg,
        "seed": seed,
    }
    return Recognizer(models, reports, {**info, **(meta or {})})


# --------------------------------------------------------------------------------------------------
# the original models


def original_hmm(mat: Mapping[str, Any], k: int, name: str = "") -> GestureHMM:
    """Model ``hmm{k}`` of an original .mat file (as read by ``scipy.io.loadmat``, not squeezed).

    Reads ``hmm{k}_prior`` (Q), ``hmm{k}_trans`` (Q×Q), ``hmm{k}_mixmat`` (Q×M), ``hmm{k}_mu`` (D×Q×M, or
    D×Q when M = 1) and ``hmm{k}_Sigma`` (D×D×Q×M, or D×D×Q).
    """
    keys = [f"hmm{k}_{v}" for v in ("prior", "trans", "mixmat", "mu", "Sigma")]
    missing = [key for key in keys if key not in mat]
    if missing:
        found = sorted(x for x in mat if not x.startswith("__"))
        raise ModelError(f"model hmm{k}: missing {', '.join(missing)}; the file has {', '.join(found)}")
    prior, trans, mixmat, mu, sigma = (np.asarray(mat[key], dtype=float) for key in keys)
    prior = prior.reshape(-1)
    Q = len(prior)
    mixmat = mixmat.reshape(Q, -1)
    M = mixmat.shape[1]
    D = mu.shape[0]
    try:
        mu = mu.reshape(D, Q, M)
        sigma = sigma.reshape(D, D, Q, M)
    except ValueError:
        raise ModelError(
            f"model hmm{k}: mu {mu.shape} / Sigma {sigma.shape} do not fit Q={Q}, M={M}"
        ) from None
    means = np.transpose(mu, (1, 2, 0))  # (Q, M, D)
    covars = np.transpose(sigma, (2, 3, 0, 1))  # (Q, M, D, D)
    return GestureHMM(prior, trans, mixmat, means, covars, name=name)


def load_original_models(
    path: str | os.PathLike,
    actions: Sequence[str] = ACTIONS,
    include_garbage: bool = False,
) -> Recognizer:
    """The originals' 2013 HMMs as a recogniser: grasp (hmm3), tap (hmm1), touch (hmm4, the push model).

    ``path`` is ``HMM_M3_Q6_mixsplit.mat`` or ``HMM_M1_Q6_mixsplit.mat``; with ``include_garbage`` the
    garbage model (hmm0) is added as action ``"garbage"``. Their inputs are the logged features / 1000.
    """
    from scipy.io import loadmat

    path = Path(path)
    if not path.is_file():
        raise ModelError(f"{path}: no such file (expected an original HMM .mat file)")
    try:
        mat = loadmat(path)
    except Exception as e:  # scipy raises several types for a malformed file
        raise ModelError(f"{path}: not a readable MATLAB file ({e})") from None
    names = list(actions) + (["garbage"] if include_garbage else [])
    models = {}
    for a in names:
        if a not in ORIGINAL_MODEL_INDEX:
            raise ModelError(f"no original model for {a!r}; allowed: {', '.join(ORIGINAL_MODEL_INDEX)}")
        try:
            models[a] = original_hmm(mat, ORIGINAL_MODEL_INDEX[a], name=a)
        except ModelError as e:
            raise ModelError(f"{path}: {e}") from None
    meta = {"source": str(path), "note": "original 2013 models; touch is the push model (hmm4)"}
    return Recognizer(models, meta=meta)
