"""glu's recipe for training gesture HMMs: time slices, one mixture per slice, then EM.

1. :func:`~glu.hmm.initialisation.init_left_to_right` starts each model from equal time slices of the
   training sequences (slice q → state q, its frames' Gaussian mixture fitted as scikit-learn's
   ``GaussianMixture`` would); with weights, from the *core* sequences (:data:`CORE_WEIGHT`), or from a
   given model;
2. Baum–Welch keeps the left-to-right structure (zero transitions stay zero under EM), with explicit
   ``n_iter`` and ``tol`` (per training frame, weighted), and the covariances are MAP estimates about the
   updated means under a weak inverse-Wishart prior ``covar_reg·I``; each sequence counts its weight
   (default 1);
3. convergence is reported (:class:`~glu.hmm.config.TrainingReport`; hmmlearn itself only logs
   non-convergence, and counts reaching ``n_iter`` as converged).

:func:`train_batch` is the one training path: it fits any number of independent models with their EM in
one batch (:func:`glu.hmm._engine.em_batch.fit_many`; one model is a batch of one), each equal to the
readable EM of :func:`glu.hmm.em.fit` to rounding (tested). Call it through :func:`glu.hmm.train`.

This is glu's recipe, not the originals' (flat start and mixture splitting, :mod:`glu.hmm.mixsplit`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

import numpy as np
from threadpoolctl import threadpool_limits

from glu.errors import ModelError
from glu.hmm._engine.em_batch import fit_many
from glu.hmm.config import TrainingConfig, TrainingReport, checked_sequences, make_report
from glu.hmm.em import FitResult, GMMHMMParams, sequence_weights
from glu.hmm.initialisation import init_left_to_right
from glu.hmm.model import GestureHMM
from glu.hmm.scoring import loglik_many, stack_models

CORE_WEIGHT = 0.5
"""Weighted training starts from the sequences whose weight is at least this fraction of the largest."""


class Problem:
    """One model's training data, checked: its sequences, their weights, its initial model, its EM ``tol``
    on the (weighted) total log-likelihood."""

    def __init__(
        self,
        sequences: Sequence[np.ndarray],
        config: TrainingConfig,
        seed: int,
        name: str,
        weights: Sequence[float] | np.ndarray | None = None,
        start: GestureHMM | None = None,
    ) -> None:
        self.name = name
        self.seqs, _ = checked_sequences(sequences, config, name)
        who = name or "the model"
        try:
            self.weights = sequence_weights(self.seqs, weights)
        except ValueError as e:
            raise ModelError(f"training data for {who}: {e}") from None
        w = self.weights
        if not np.any(w > 0):
            raise ModelError(f"training data for {who}: every sequence has weight 0")
        self.used = [X for X, x in zip(self.seqs, w, strict=True) if x > 0]
        self.weighted_frames = float(w @ np.array([len(X) for X in self.seqs]))
        if start is None:
            core = [X for X, x in zip(self.seqs, w, strict=True) if x >= CORE_WEIGHT * w.max()]
            if sum(len(X) for X in core) < config.n_states * config.n_mix:
                core = self.used
            checked_sequences(core, config, name)
            start = init_left_to_right(core, config.n_states, config.n_mix, config.covar_reg, seed, name)
        self.init = GMMHMMParams(start.startprob, start.transmat, start.weights, start.means, start.covars)
        self.tol = config.tol * self.weighted_frames


def train_batch(
    sequences: Sequence[Sequence[np.ndarray]],
    config: TrainingConfig,
    seeds: Sequence[int],
    names: Sequence[str],
    warn: bool = True,
    weights: Sequence[Sequence[float] | np.ndarray | None] | None = None,
    starts: Sequence[GestureHMM | None] | None = None,
    progress: Callable[[int], None] | None = None,
) -> list[tuple[GestureHMM, TrainingReport]]:
    """Fit left-to-right GMM-HMMs by glu's recipe, one per entry of ``sequences``, EM batched.

    Parameters
    ----------
    sequences : one list of training sequences (arrays of shape (T_i, D)) per model
    config : Q, M, the EM limits (``tol`` per training frame, so it means the same for any amount of data;
        hmmlearn's own ``tol`` is this times the number of frames) and ``covar_reg``: each covariance is
        ``Σ = (S + covar_reg·I) / (N + 1)`` for scatter S and soft count N, so a component with few frames
        cannot collapse
    seeds, names : one per model: the initial mixtures' seed, the action (for messages and the report)
    warn : emit an :class:`~glu.hmm.config.HMMConvergenceWarning` when EM does not converge
    weights : per model, one weight ≥ 0 per sequence (None: every weight 1); with weights ``tol`` is per
        weighted frame, and the report counts the sequences of positive weight and weighs its
        log-likelihoods
    starts : per model, a model EM goes on from instead of a fresh initial model (None: fresh)
    progress : called with the number of models that have just finished

    Returns
    -------
    (model, report) per entry of ``sequences``, in order. When EM fails for some model, every model is
    trained again alone so that the error (:class:`~glu.errors.ModelError`) names the model.
    """
    n = len(sequences)
    ws = list(weights) if weights is not None else [None] * n
    firsts = list(starts) if starts is not None else [None] * n
    jobs = list(zip(sequences, seeds, names, ws, firsts, strict=True))
    with threadpool_limits(1):
        problems = [Problem(seqs, config, sd, nm, w, first) for seqs, sd, nm, w, first in jobs]
        try:  # Baum–Welch of every problem in one batch
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("ignore", RuntimeWarning)
                results = fit_many(
                    [(p.seqs, p.init) for p in problems],
                    config.n_iter,
                    [p.tol for p in problems],
                    config.covar_reg,
                    "map",
                    weights=[p.weights for p in problems],
                    progress=progress,
                )
        except (ValueError, np.linalg.LinAlgError) as e:
            if n == 1:
                raise ModelError(f"EM failed for {problems[0].name or 'the model'}: {e}") from None
            results = None
    if results is None:  # say which model failed
        return [train_batch([s], config, [sd], [nm], warn, [w], [f])[0] for s, sd, nm, w, f in jobs]
    return [_finish(p, r, config, warn) for p, r in zip(problems, results, strict=True)]


def _finish(
    p: Problem, result: FitResult, config: TrainingConfig, warn: bool
) -> tuple[GestureHMM, TrainingReport]:
    """The fitted model and its report (warning when EM did not converge)."""
    try:
        fitted = GestureHMM(*result.params, name=p.name)
    except ModelError as e:
        raise ModelError(f"EM diverged for {p.name or 'the model'} ({e}); try a larger covar_reg") from None
    # the (weighted) training log-likelihood under the returned model, all sequences in one batch (the
    # same numbers as fitted.loglik of each; summed in order)
    ll = loglik_many(stack_models([fitted]), p.seqs)[:, 0]
    final = float(sum((w * x for w, x in zip(p.weights.tolist(), ll.tolist(), strict=True) if w > 0), 0.0))
    history = tuple(float(h) for h in result.history)
    report = make_report(
        p.name, p.used, history, len(history), final, config.tol, config.n_iter, warn, p.weighted_frames
    )
    return fitted, report
