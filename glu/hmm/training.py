"""Training gesture HMMs: the settings, glu's initialisation, EM, and what happened.

* :class:`TrainingConfig` is the one home of the training defaults (Q = 6 states, M = 3 Gaussians, the
  originals' model size; EM limits; the covariance regulariser). The command line, the experiments and the
  notebooks' checks all read them from here.
* :func:`init_left_to_right` starts each model from equal time slices of the training sequences;
  :func:`train_hmm` runs Baum–Welch keeping the left-to-right structure (zero transitions stay zero
  under EM), with explicit ``n_iter`` and ``tol``, and reports convergence (:class:`TrainingReport`;
  hmmlearn itself only logs non-convergence, and counts reaching ``n_iter`` as converged). EM is
  vectorised over the training sequences (:mod:`glu.gestures.baum_welch`), with the MAP covariance about
  the updated means; ``engine="hmmlearn"`` runs hmmlearn's ``GMMHMM`` instead, whose covariance step
  uses the means before the update.

This is glu's recipe, not the originals' (flat start and mixture splitting, METHOD.md §5.1), which is
:mod:`glu.gestures.mixsplit`; ``glu hmm train --recipe`` chooses between them.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from glu.errors import DataError, ModelError
from glu.gestures.batch import loglik_many, stack_models
from glu.gestures.forward import left_to_right_transmat
from glu.gestures.gmm_init import fit_gaussian_mixture
from glu.gestures.model import GestureHMM, as_sequence


class HMMConvergenceWarning(UserWarning):
    """EM stopped without converging (iteration limit reached, or the log-likelihood decreased)."""


@dataclass(frozen=True)
class TrainingConfig:
    """How gesture HMMs are trained (the defaults are glu's, used everywhere).

    Attributes
    ----------
    n_states : Q, states per model (the originals': 6)
    n_mix : M, Gaussians per state (the originals': 3)
    n_iter : most EM iterations
    tol : EM tolerance, in log-likelihood per training frame
    covar_reg : strength of the weak inverse-Wishart prior on each covariance, a pseudo-scatter
        ``covar_reg·I`` (feature units², so 0.03 is a prior spread of about 0.17 units, 5 cm). Chosen by
        leave-one-segment-out on the 11 standing real segments, not on the test gestures: 0.03 gives 0.73
        (raw features) and 1.00 (centred) over seeds 0–2, where 0.001 gave 0.45 and 0.73–0.82, and on
        synthetic gestures 5-fold accuracy 0.97 against 0.93–0.95 (notebook 10, ``hmm_feature_settings``)
    """

    n_states: int = 6
    n_mix: int = 3
    n_iter: int = 200
    tol: float = 1e-4
    covar_reg: float = 0.03

    def as_dict(self) -> dict[str, Any]:
        """The settings as keyword arguments of :func:`train_hmm`."""
        return asdict(self)


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
    n_states: int = TrainingConfig.n_states,
    n_mix: int = TrainingConfig.n_mix,
    seed: int = 0,
    covar_reg: float = TrainingConfig.covar_reg,
    name: str = "",
) -> GestureHMM:
    """An initial left-to-right model: each sequence cut into ``n_states`` equal time slices, slice q → state q.

    The frames of slice q (over all sequences) give state q's mixture (scikit-learn's ``GaussianMixture``
    fit, seeded, as :func:`~glu.gestures.gmm_init.fit_gaussian_mixture` computes it without scikit-learn; with too few frames,
    one Gaussian copied ``n_mix`` times with means spread along its main axis). Self-transition probabilities are ``1 - 1 / (mean frames per state)``, clipped to [0.5, 0.98].
    ``sequences`` are arrays of shape (T_i, D).
    """
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
            weights[q], means[q], covars[q] = fit_gaussian_mixture(Xq, n_mix, covar_reg, seed)
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


ENGINES: tuple[str, ...] = ("glu", "hmmlearn")
"""Who runs EM: glu's vectorised Baum–Welch (the default; the covariance is the MAP estimate about the
updated mean) or hmmlearn's ``GMMHMM.fit`` (which takes the scatter about the mean before the update)."""


def train_hmm(
    sequences: Sequence[np.ndarray],
    n_states: int = TrainingConfig.n_states,
    n_mix: int = TrainingConfig.n_mix,
    *,
    n_iter: int = TrainingConfig.n_iter,
    tol: float = TrainingConfig.tol,
    covar_reg: float = TrainingConfig.covar_reg,
    seed: int = 0,
    name: str = "",
    warn: bool = True,
    engine: str = "glu",
) -> tuple[GestureHMM, TrainingReport]:
    """Fit a left-to-right GMM-HMM to sequences of shape (T_i, D) by EM (Baum–Welch).

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
    engine : ``"glu"`` (vectorised, :mod:`glu.gestures.baum_welch`, ``covariance="map"``) or
        ``"hmmlearn"`` (its ``GMMHMM``, whose covariance step uses the pre-update means; glu's engine with
        ``covariance="hmmlearn"`` is tested equal to it)

    Returns
    -------
    the model and a :class:`TrainingReport`. Zero transitions of the left-to-right initialisation stay
    zero (EM cannot create transitions that have zero probability).
    """
    if engine not in ENGINES:
        raise ModelError(f"unknown EM engine {engine!r}; allowed: {', '.join(ENGINES)}")
    seqs, n_frames = _checked(sequences, n_states, n_mix, n_iter, tol, name)
    from threadpoolctl import threadpool_limits

    # one thread for BLAS and OpenMP: the many small linear-algebra calls are several times slower with
    # thread hand-offs (and the sweeps parallelise over models instead)
    with threadpool_limits(1):
        init = init_left_to_right(seqs, n_states, n_mix, seed, covar_reg, name)
        fitted_params, history = _run_em(engine, seqs, init, n_iter, tol * n_frames, covar_reg, seed, name)
    return _finish(seqs, fitted_params, history, tol, n_iter, name, warn)


def _checked(
    sequences: Sequence[np.ndarray], n_states: int, n_mix: int, n_iter: int, tol: float, name: str
) -> tuple[list[np.ndarray], int]:
    """The training sequences as float arrays (T_i, D) and their number of frames, or a clear error."""
    who = f"training data for {name!r}" if name else "training data"
    if len(sequences) == 0:
        raise DataError(f"{who}: no sequences")
    D = np.asarray(sequences[0]).shape[-1] if np.asarray(sequences[0]).ndim == 2 else 3
    seqs = [as_sequence(X, D, f"{who}, sequence {i + 1}") for i, X in enumerate(sequences)]
    n_frames = sum(len(X) for X in seqs)
    if n_states < 1 or n_mix < 1:
        raise ModelError(f"n_states={n_states} and n_mix={n_mix} must be ≥ 1")
    if n_frames < n_states * n_mix:
        raise DataError(f"{who}: {n_frames} frames are too few for {n_states} states × {n_mix} mixtures")
    if n_iter < 1 or not tol > 0:
        raise ModelError(f"n_iter={n_iter} must be ≥ 1 and tol={tol} > 0")
    return seqs, n_frames


def _finish(
    seqs: list[np.ndarray],
    fitted_params: tuple[np.ndarray, ...],
    history: tuple[float, ...],
    tol: float,
    n_iter: int,
    name: str,
    warn: bool,
) -> tuple[GestureHMM, TrainingReport]:
    """The fitted model and its :class:`TrainingReport` (warning when EM did not converge)."""
    try:
        fitted = GestureHMM(*fitted_params, name=name)
    except ModelError as e:
        raise ModelError(f"EM diverged for {name or 'the model'} ({e}); try a larger covar_reg") from None
    n_frames = sum(len(X) for X in seqs)
    delta = history[-1] - history[-2] if len(history) >= 2 else math.inf
    converged = bool(abs(delta) < tol * n_frames)
    # the training sequences' log-likelihood under the returned model, all sequences in one batch (the
    # same numbers as fitted.loglik of each; summed in the same order)
    final = float(sum(loglik_many(stack_models([fitted]), seqs)[:, 0].tolist()))
    report = TrainingReport(name, len(seqs), n_frames, len(history), converged, history, final, tol, n_iter)
    if not converged and warn:
        warnings.warn(report.describe(), HMMConvergenceWarning, stacklevel=3)
    return fitted, report


def train_many(
    sequences: Sequence[Sequence[np.ndarray]],
    n_states: int = TrainingConfig.n_states,
    n_mix: int = TrainingConfig.n_mix,
    *,
    n_iter: int = TrainingConfig.n_iter,
    tol: float = TrainingConfig.tol,
    covar_reg: float = TrainingConfig.covar_reg,
    seed: int | Sequence[int] = 0,
    name: str | Sequence[str] = "",
    warn: bool = True,
) -> list[tuple[GestureHMM, TrainingReport]]:
    """:func:`train_hmm` (glu's engine) for many independent models at once, EM batched.

    Parameters
    ----------
    sequences : one list of training sequences (arrays of shape (T_i, D)) per model
    n_states, n_mix, n_iter, tol, covar_reg, warn : as :func:`train_hmm`, the same for every model
    seed, name : one for all models, or one per model

    Returns
    -------
    (model, report) per entry of ``sequences``, in order: what ``train_hmm`` returns for it (the same
    initialisation; Baum–Welch by :func:`glu.gestures.baum_welch_batch.fit_many`, equal to the one-model
    EM to rounding, tested). When EM fails for some model, every model is retrained alone so the error
    names the model, as ``train_hmm`` would.
    """
    n = len(sequences)
    seeds = [seed] * n if isinstance(seed, int | np.integer) else list(seed)
    names = [name] * n if isinstance(name, str) else list(name)
    if len(seeds) != n or len(names) != n:
        raise ModelError(f"{n} training sets need as many seeds and names, got {len(seeds)} and {len(names)}")
    checked = [
        _checked(seqs, n_states, n_mix, n_iter, tol, nm) for seqs, nm in zip(sequences, names, strict=True)
    ]
    from threadpoolctl import threadpool_limits

    from glu.gestures import baum_welch as bw
    from glu.gestures.baum_welch_batch import fit_many

    with threadpool_limits(1):
        problems = []
        for (seqs, _), sd, nm in zip(checked, seeds, names, strict=True):
            init = init_left_to_right(seqs, n_states, n_mix, sd, covar_reg, nm)
            problems.append(
                (seqs, bw.GMMHMMParams(init.startprob, init.transmat, init.weights, init.means, init.covars))
            )
        try:
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("ignore", RuntimeWarning)
                results = fit_many(problems, n_iter, [tol * f for _, f in checked], covar_reg, "map")
        except (ValueError, np.linalg.LinAlgError):  # say which model failed, as train_hmm does
            kw = dict(n_iter=n_iter, tol=tol, covar_reg=covar_reg, warn=warn)
            return [
                train_hmm(seqs, n_states, n_mix, seed=sd, name=nm, **kw)
                for (seqs, _), sd, nm in zip(checked, seeds, names, strict=True)
            ]
    return [
        _finish(seqs, tuple(r.params), tuple(float(h) for h in r.history), tol, n_iter, nm, warn)
        for (seqs, _), r, nm in zip(checked, results, names, strict=True)
    ]


def _run_em(
    engine: str,
    seqs: list[np.ndarray],
    init: GestureHMM,
    n_iter: int,
    tol_total: float,
    covar_reg: float,
    seed: int,
    name: str,
) -> tuple[tuple[np.ndarray, ...], tuple[float, ...]]:
    """EM from ``init``: the fitted (startprob, transmat, weights, means, covars) and the history."""
    start = (init.startprob, init.transmat, init.weights, init.means, init.covars)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore", RuntimeWarning)
            if engine == "glu":
                from glu.gestures import baum_welch

                result = baum_welch.fit(
                    seqs, baum_welch.GMMHMMParams(*start), n_iter, tol_total, covar_reg, "map"
                )
                return tuple(result.params), tuple(float(h) for h in result.history)
            return _run_hmmlearn(seqs, start, n_iter, tol_total, covar_reg, seed)
    except (ValueError, np.linalg.LinAlgError) as e:
        raise ModelError(f"EM failed for {name or 'the model'}: {e}") from None


def _run_hmmlearn(
    seqs: list[np.ndarray],
    start: tuple[np.ndarray, ...],
    n_iter: int,
    tol_total: float,
    covar_reg: float,
    seed: int,
) -> tuple[tuple[np.ndarray, ...], tuple[float, ...]]:
    import logging

    D = seqs[0].shape[1]
    n_states, n_mix = start[2].shape
    model = _preset_gmmhmm_class()(
        n_components=n_states,
        n_mix=n_mix,
        covariance_type="full",
        n_iter=n_iter,
        tol=tol_total,
        params="stmcw",
        init_params="",
        random_state=seed,
        implementation="log",
        covars_prior=covar_reg * np.eye(D),
        covars_weight=-(D + 1.0),
    )
    model.startprob_, model.transmat_, model.weights_, model.means_, model.covars_ = (a.copy() for a in start)
    hmm_log = logging.getLogger("hmmlearn.base")
    level = hmm_log.level
    hmm_log.setLevel(logging.ERROR)  # we report non-convergence ourselves
    try:
        model.fit(np.concatenate(seqs), [len(X) for X in seqs])
    finally:
        hmm_log.setLevel(level)
    params = (model.startprob_, model.transmat_, model.weights_, model.means_, model.covars_)
    return params, tuple(float(h) for h in model.monitor_.history)
