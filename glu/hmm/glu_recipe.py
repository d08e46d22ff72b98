"""glu's recipe for training a gesture HMM: time slices, one mixture per slice, then EM.

1. :func:`~glu.hmm.initialisation.init_left_to_right` starts each model from equal time slices of the
   training sequences (slice q → state q, its frames' Gaussian mixture fitted as scikit-learn's
   ``GaussianMixture`` would);
2. Baum–Welch (:func:`glu.hmm.em.fit`) keeps the left-to-right structure (zero transitions stay zero under
   EM), with explicit ``n_iter`` and ``tol``, and the covariances are MAP estimates about the updated means
   under a weak inverse-Wishart prior ``covar_reg·I``;
3. convergence is reported (:class:`~glu.hmm.config.TrainingReport`; hmmlearn itself only logs
   non-convergence, and counts reaching ``n_iter`` as converged).

:func:`train_one` fits one model with the readable EM of :mod:`glu.hmm.em` (or hmmlearn's ``GMMHMM`` with
``engine="hmmlearn"``, whose covariance step uses the means before the update); :func:`train_batch` fits
many independent models with their EM batched (:mod:`glu.hmm._engine.em_batch`), each equal to
:func:`train_one`'s to rounding (tested). Call them through :func:`glu.hmm.train`.

This is glu's recipe, not the originals' (flat start and mixture splitting, :mod:`glu.hmm.mixsplit`).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np

from glu.errors import ModelError
from glu.hmm import em
from glu.hmm._engine.batch import loglik_many, stack_models
from glu.hmm._engine.em_batch import fit_many
from glu.hmm._engine.online import expected_stats_fast, fit_weighted_fast
from glu.hmm.config import (
    ENGINES,
    HMMConvergenceWarning,
    TrainingConfig,
    TrainingReport,
    checked_sequences,
    make_report,
)
from glu.hmm.initialisation import init_left_to_right
from glu.hmm.model import GestureHMM


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


def train_one(
    sequences: Sequence[np.ndarray],
    config: TrainingConfig,
    seed: int = 0,
    name: str = "",
    warn: bool = True,
    engine: str = "glu",
) -> tuple[GestureHMM, TrainingReport]:
    """Fit one left-to-right GMM-HMM to sequences of shape (T_i, D) by glu's recipe.

    Parameters
    ----------
    sequences : the training sequences, each an array of shape (T_i, D)
    config : Q, M, the EM limits (``tol`` per training frame, so it means the same for any amount of data;
        hmmlearn's own ``tol`` is this times the number of frames) and ``covar_reg``: each covariance is
        ``Σ = (S + covar_reg·I) / (N + 1)`` for scatter S and soft count N, so a component with few frames
        cannot collapse
    seed : seeds the initial mixtures
    name : the action (for messages and the report)
    warn : emit an :class:`~glu.hmm.config.HMMConvergenceWarning` when EM does not converge
    engine : ``"glu"`` (:func:`glu.hmm.em.fit`, ``covariance="map"``) or ``"hmmlearn"`` (its ``GMMHMM``;
        :func:`glu.hmm.em.fit` with ``covariance="hmmlearn"`` is tested equal to it)
    """
    if engine not in ENGINES:
        raise ModelError(f"unknown EM engine {engine!r}; allowed: {', '.join(ENGINES)}")
    seqs, n_frames = checked_sequences(sequences, config, name)
    from threadpoolctl import threadpool_limits

    # one thread for BLAS and OpenMP: the many small linear-algebra calls are several times slower with
    # thread hand-offs (and the sweeps parallelise over models instead)
    with threadpool_limits(1):
        init = init_left_to_right(seqs, config.n_states, config.n_mix, config.covar_reg, seed, name)
        fitted_params, history = _run_em(engine, seqs, init, config, config.tol * n_frames, seed, name)
    return _finish(seqs, fitted_params, history, config, name, warn)


def _finish(
    seqs: list[np.ndarray],
    fitted_params: tuple[np.ndarray, ...],
    history: tuple[float, ...],
    config: TrainingConfig,
    name: str,
    warn: bool,
) -> tuple[GestureHMM, TrainingReport]:
    """The fitted model and its report (warning when EM did not converge)."""
    try:
        fitted = GestureHMM(*fitted_params, name=name)
    except ModelError as e:
        raise ModelError(f"EM diverged for {name or 'the model'} ({e}); try a larger covar_reg") from None
    # the training sequences' log-likelihood under the returned model, all sequences in one batch (the
    # same numbers as fitted.loglik of each; summed in the same order)
    final = float(sum(loglik_many(stack_models([fitted]), seqs)[:, 0].tolist()))
    report = make_report(name, seqs, history, len(history), final, config.tol, config.n_iter, warn)
    return fitted, report


def train_batch(
    sequences: Sequence[Sequence[np.ndarray]],
    config: TrainingConfig,
    seeds: Sequence[int],
    names: Sequence[str],
    warn: bool = True,
) -> list[tuple[GestureHMM, TrainingReport]]:
    """:func:`train_one` for many independent models at once, EM batched.

    Parameters
    ----------
    sequences : one list of training sequences (arrays of shape (T_i, D)) per model
    config, warn : as :func:`train_one`, the same for every model
    seeds, names : one per model

    Returns
    -------
    (model, report) per entry of ``sequences``, in order: what :func:`train_one` returns for it (the same
    initialisation; Baum–Welch by :func:`glu.hmm._engine.em_batch.fit_many`, equal to the one-model EM to
    rounding, tested). When EM fails for some model, every model is retrained alone so the error names
    the model, as :func:`train_one` would.
    """
    checked = [checked_sequences(seqs, config, nm) for seqs, nm in zip(sequences, names, strict=True)]
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        problems = []
        for (seqs, _), sd, nm in zip(checked, seeds, names, strict=True):
            init = init_left_to_right(seqs, config.n_states, config.n_mix, config.covar_reg, sd, nm)
            problems.append(
                (seqs, em.GMMHMMParams(init.startprob, init.transmat, init.weights, init.means, init.covars))
            )
        try:
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("ignore", RuntimeWarning)
                tols = [config.tol * f for _, f in checked]
                results = fit_many(problems, config.n_iter, tols, config.covar_reg, "map")
        except (ValueError, np.linalg.LinAlgError):  # say which model failed, as train_one does
            return [
                train_one(seqs, config, sd, nm, warn)
                for (seqs, _), sd, nm in zip(checked, seeds, names, strict=True)
            ]
    return [
        _finish(seqs, tuple(r.params), tuple(float(h) for h in r.history), config, nm, warn)
        for (seqs, _), r, nm in zip(checked, results, names, strict=True)
    ]


CORE_WEIGHT = 0.5
"""Weighted training starts from the sequences whose weight is at least this fraction of the largest."""


def train_weighted(
    sequences: Sequence[np.ndarray],
    weights: Sequence[float] | np.ndarray,
    config: TrainingConfig,
    seed: int = 0,
    name: str = "",
    warn: bool = True,
    start: GestureHMM | None = None,
) -> tuple[GestureHMM, TrainingReport]:
    """Fit one model to weighted sequences: each of shape (T_i, D) counts ``weights[i]`` times (≥ 0).

    The initial model is ``start`` if given (EM goes on from it), else
    :func:`~glu.hmm.initialisation.init_left_to_right` of the *core* sequences, those weighing at least
    :data:`CORE_WEIGHT` of the heaviest (all of positive weight when the core has too few frames); then
    weighted Baum–Welch (:func:`glu.hmm.em.fit_weighted`, the ``map`` covariance of glu's recipe; run by
    its compiled twin :func:`glu.hmm._engine.online.fit_weighted_fast`, equal to rounding), ``tol`` per
    weighted training frame. The report counts the sequences of positive weight; its log-likelihoods are
    weighted.
    """
    seqs, _ = checked_sequences(sequences, config, name)
    try:
        w = em.sequence_weights(seqs, weights)
    except ValueError as e:
        raise ModelError(f"training data for {name or 'the model'}: {e}") from None
    if not np.any(w > 0):
        raise ModelError(f"training data for {name or 'the model'}: every sequence has weight 0")
    used = [X for X, x in zip(seqs, w, strict=True) if x > 0]
    core = [X for X, x in zip(seqs, w, strict=True) if x >= CORE_WEIGHT * w.max()]
    if sum(len(X) for X in core) < config.n_states * config.n_mix:
        core = used
    checked_sequences(core, config, name)
    weighted_frames = float(w @ np.array([len(X) for X in seqs]))
    if start is None:
        start = init_left_to_right(core, config.n_states, config.n_mix, config.covar_reg, seed, name)
    first = em.GMMHMMParams(start.startprob, start.transmat, start.weights, start.means, start.covars)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore", RuntimeWarning)
            result = fit_weighted_fast(
                seqs, w, first, config.n_iter, config.tol * weighted_frames, config.covar_reg, "map"
            )
    except (ValueError, np.linalg.LinAlgError) as e:
        raise ModelError(f"EM failed for {name or 'the model'}: {e}") from None
    try:
        fitted = GestureHMM(*result.params, name=name)
    except ModelError as e:
        raise ModelError(f"EM diverged for {name or 'the model'} ({e}); try a larger covar_reg") from None
    final = float(expected_stats_fast(seqs, em.GMMHMMParams(*result.params), w).loglik)
    history = tuple(float(h) for h in result.history)
    delta = history[-1] - history[-2] if len(history) >= 2 else float("inf")
    converged = bool(abs(delta) < config.tol * weighted_frames)
    report = TrainingReport(
        name,
        len(used),
        sum(len(X) for X in used),
        len(history),
        converged,
        history,
        final,
        config.tol,
        config.n_iter,
    )
    if not converged and warn:
        warnings.warn(report.describe(), HMMConvergenceWarning, stacklevel=3)
    return fitted, report


def _run_em(
    engine: str,
    seqs: list[np.ndarray],
    init: GestureHMM,
    config: TrainingConfig,
    tol_total: float,
    seed: int,
    name: str,
) -> tuple[tuple[np.ndarray, ...], tuple[float, ...]]:
    """EM from ``init``: the fitted (startprob, transmat, weights, means, covars) and the history."""
    start = (init.startprob, init.transmat, init.weights, init.means, init.covars)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore", RuntimeWarning)
            if engine == "glu":
                result = em.fit(
                    seqs, em.GMMHMMParams(*start), config.n_iter, tol_total, config.covar_reg, "map"
                )
                return tuple(result.params), tuple(float(h) for h in result.history)
            return _run_hmmlearn(seqs, start, config.n_iter, tol_total, config.covar_reg, seed)
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
