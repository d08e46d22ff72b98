"""The originals' HMM training recipe, "mixsplit": flat start, Baum–Welch, mixture splitting (METHOD.md §5.1).

Saponaro's thesis (appendix on gesture recognition) trained the 2013 models
(``HMM_M3_Q6_mixsplit.mat``) like this:

1. **flat start** (:func:`flat_start`): a left-to-right model in which every state emits one Gaussian with
   the global mean and covariance of all training frames; each state stays with probability 0.5 and moves
   on with 0.5 (the last state stays); the first state starts;
2. **Baum–Welch** until the log-likelihood gains less than ``tol`` per training frame;
3. **split** (:func:`split_heaviest`): in every state the component of largest weight becomes two, with
   means ``μ ± 0.2·√diag(Σ)``, the covariance copied and half the weight each; then Baum–Welch again;
   repeated until every state has M components.

The variable names of the original files (``prior``, ``trans``, ``mu``, ``Sigma``, ``mixmat``) are those of
K. Murphy's HMM toolbox, whose Gaussian M-step adds ``0.01·I`` to every re-estimated covariance; the
original models' covariances all have eigenvalues above 0.01 (the smallest is 0.0108), as that floor
implies. :data:`COVAR_FLOOR` reproduces it: covariances are the maximum-likelihood ones plus
``covar_floor·I`` (``covar_floor = 0`` is plain maximum likelihood, for which the log-likelihood never
decreases within a stage). A component that loses all its frames keeps its previous covariance.

glu's own recipe (:mod:`glu.gestures.training`) starts instead from equal time slices of each sequence,
fits all M components of a slice at once (scikit-learn ``GaussianMixture``) and regularises covariances
with a weak inverse-Wishart prior; :data:`RECIPES` names both and ``glu hmm train --recipe`` chooses.
Baum–Welch is :func:`glu.gestures.baum_welch.fit` in both (``ml`` covariances here, ``map`` in glu's).

Example
-------
>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> seqs = [np.cumsum(rng.normal(size=(40, 3)), axis=0) for _ in range(4)]
>>> hmm, report, stages = train_mixsplit(seqs, n_states=3, n_mix=2, name="tap")
>>> hmm.n_states, hmm.n_mix, len(stages), hmm.is_left_to_right
(3, 2, 2, True)
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np

from glu.errors import DataError, ModelError
from glu.gestures.forward import left_to_right_transmat
from glu.gestures.model import GestureHMM, as_sequence
from glu.gestures.training import HMMConvergenceWarning, TrainingConfig, TrainingReport

RECIPES: tuple[str, ...] = ("glu", "mixsplit")
"""How gesture HMMs can be trained: ``glu`` (time slices + GaussianMixture, :func:`glu.gestures.training.train_hmm`)
or ``mixsplit`` (the originals': flat start and mixture splitting, :func:`train_mixsplit`)."""
SPLIT_OFFSET = 0.2
"""A split moves the two new means this many standard deviations (per coordinate) apart from the old one."""
FLAT_STAY = 0.5
"""Self-transition probability of the flat start."""
COVAR_FLOOR = 0.01
"""Added to every re-estimated covariance (times the identity), as the originals' toolbox did (in the
units of the original models: the logged coordinates / 1000)."""
_EMPTY = 1e-10
"""A component with less soft count than this has lost its frames: its covariance is kept."""


def flat_start(sequences: Sequence[np.ndarray], n_states: int, name: str = "") -> GestureHMM:
    """The flat-start model: every state one Gaussian with the global mean and covariance, 0.5 stay / 0.5 next.

    ``sequences`` are arrays of shape (T_i, D); the covariance is the maximum-likelihood one of all their
    frames pooled (divided by the number of frames).
    """
    X = np.concatenate(sequences)
    D = X.shape[1]
    mean = X.mean(axis=0)
    cov = np.cov(X.T, bias=True).reshape(D, D)
    startprob = np.zeros(n_states)
    startprob[0] = 1.0
    return GestureHMM(
        startprob,
        left_to_right_transmat(n_states, FLAT_STAY),
        np.ones((n_states, 1)),
        np.tile(mean, (n_states, 1, 1)),
        np.tile(cov, (n_states, 1, 1, 1)),
        name=name,
    )


def split_heaviest(hmm: GestureHMM, offset: float = SPLIT_OFFSET) -> GestureHMM:
    """One more component per state: the heaviest component of each state split in two.

    The two halves have means ``μ ± offset·√diag(Σ)``, the covariance ``Σ`` copied and half the weight
    each; the new component is appended last. Transitions are kept. Returns a model with ``n_mix + 1``.
    """
    Q, M, D = hmm.means.shape
    weights = np.zeros((Q, M + 1))
    means = np.zeros((Q, M + 1, D))
    covars = np.zeros((Q, M + 1, D, D))
    weights[:, :M], means[:, :M], covars[:, :M] = hmm.weights, hmm.means, hmm.covars
    for q in range(Q):
        j = int(np.argmax(hmm.weights[q]))
        delta = offset * np.sqrt(np.diag(hmm.covars[q, j]))
        means[q, j], means[q, M] = hmm.means[q, j] + delta, hmm.means[q, j] - delta
        covars[q, M] = hmm.covars[q, j]
        weights[q, j] = weights[q, M] = hmm.weights[q, j] / 2
    return GestureHMM(hmm.startprob, hmm.transmat, weights, means, covars, name=hmm.name)


def baum_welch(
    hmm: GestureHMM,
    sequences: Sequence[np.ndarray],
    n_iter: int = TrainingConfig.n_iter,
    tol: float = TrainingConfig.tol,
    covar_floor: float = COVAR_FLOOR,
) -> tuple[GestureHMM, tuple[float, ...]]:
    """Baum–Welch from ``hmm``, every parameter re-estimated (:func:`glu.gestures.baum_welch.fit`).

    Covariances are the maximum-likelihood ones (about the updated means, as the originals' toolbox
    computed them) plus ``covar_floor·I``; a component that lost its frames keeps its covariance. Stops
    after ``n_iter`` iterations or when the total log-likelihood gains less than ``tol`` × the number of
    frames. Returns the model and the total log-likelihood before each M-step.
    """
    from threadpoolctl import threadpool_limits

    from glu.gestures import baum_welch as bw

    n_frames = sum(len(X) for X in sequences)
    start = bw.GMMHMMParams(hmm.startprob, hmm.transmat, hmm.weights, hmm.means, hmm.covars)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"), threadpool_limits(1):
            warnings.simplefilter("ignore", RuntimeWarning)
            result = bw.fit(
                sequences, start, n_iter, tol * n_frames, covariance="ml", covar_floor=covar_floor
            )
    except (ValueError, np.linalg.LinAlgError) as e:
        raise ModelError(f"Baum–Welch failed for {hmm.name or 'the model'} at M = {hmm.n_mix}: {e}") from None
    try:
        fitted = GestureHMM(*result.params, name=hmm.name)
    except ModelError as e:
        raise ModelError(
            f"Baum–Welch diverged for {hmm.name or 'the model'} at M = {hmm.n_mix} ({e}); try covar_floor > 0"
        ) from None
    return fitted, tuple(float(h) for h in result.history)


def train_mixsplit(
    sequences: Sequence[np.ndarray],
    n_states: int = TrainingConfig.n_states,
    n_mix: int = TrainingConfig.n_mix,
    *,
    n_iter: int = TrainingConfig.n_iter,
    tol: float = TrainingConfig.tol,
    covar_floor: float = COVAR_FLOOR,
    name: str = "",
    warn: bool = True,
    seed: int | None = None,
    covar_reg: float | None = None,
) -> tuple[GestureHMM, TrainingReport, list[tuple[float, ...]]]:
    """Train a left-to-right GMM-HMM by the originals' recipe: flat start, Baum–Welch, split, Baum–Welch, …

    Parameters
    ----------
    sequences : the training sequences, each an array of shape (T_i, D)
    n_states, n_mix : Q and the final M (stages M = 1, 2, …, n_mix)
    n_iter, tol : per stage, at most ``n_iter`` Baum–Welch iterations, stopping when the log-likelihood
        gains less than ``tol`` per training frame
    covar_floor : added to every re-estimated covariance, times the identity (the originals': 0.01; 0: ML)
    name : the action (for messages)
    warn : emit an :class:`~glu.gestures.training.HMMConvergenceWarning` when the last stage did not converge
    seed, covar_reg : ignored (the recipe is deterministic and has its own regulariser, ``covar_floor``);
        accepted so both recipes take the same arguments

    Returns
    -------
    the model, a :class:`~glu.gestures.training.TrainingReport` of the last stage (``n_iter`` counts every
    stage's iterations), and the log-likelihood history of each stage (M = 1 first).
    """
    seqs, n_frames = _checked(sequences, n_states, n_mix, n_iter, tol, covar_floor, name)
    hmm = flat_start(seqs, n_states, name)
    stages: list[tuple[float, ...]] = []
    while True:
        hmm, history = baum_welch(hmm, seqs, n_iter, tol, covar_floor)
        stages.append(history)
        if hmm.n_mix >= n_mix:
            break
        hmm = split_heaviest(hmm)
    return (*_finish(hmm, seqs, stages, tol, n_iter, n_mix, name, warn), stages)


def _checked(
    sequences: Sequence[np.ndarray],
    n_states: int,
    n_mix: int,
    n_iter: int,
    tol: float,
    covar_floor: float,
    name: str,
) -> tuple[list[np.ndarray], int]:
    who = f"training data for {name!r}" if name else "training data"
    if len(sequences) == 0:
        raise DataError(f"{who}: no sequences")
    first = np.asarray(sequences[0])
    D = first.shape[-1] if first.ndim == 2 else 3
    seqs = [as_sequence(X, D, f"{who}, sequence {i + 1}") for i, X in enumerate(sequences)]
    n_frames = sum(len(X) for X in seqs)
    if n_states < 1 or n_mix < 1:
        raise ModelError(f"n_states={n_states} and n_mix={n_mix} must be ≥ 1")
    if n_frames < n_states * n_mix:
        raise DataError(f"{who}: {n_frames} frames are too few for {n_states} states × {n_mix} mixtures")
    if n_iter < 1 or not tol > 0 or not covar_floor >= 0:
        raise ModelError(f"n_iter={n_iter} must be ≥ 1, tol={tol} > 0 and covar_floor={covar_floor} ≥ 0")
    return seqs, n_frames


def _finish(
    hmm: GestureHMM,
    seqs: list[np.ndarray],
    stages: list[tuple[float, ...]],
    tol: float,
    n_iter: int,
    n_mix: int,
    name: str,
    warn: bool,
) -> tuple[GestureHMM, TrainingReport]:
    n_frames = sum(len(X) for X in seqs)
    last = stages[-1]
    delta = last[-1] - last[-2] if len(last) >= 2 else math.inf
    converged = bool(abs(delta) < tol * n_frames)
    final = float(sum(hmm.loglik(X) for X in seqs))
    report = TrainingReport(
        name, len(seqs), n_frames, sum(len(h) for h in stages), converged, last, final, tol, n_iter * n_mix
    )
    if not converged and warn:
        warnings.warn(report.describe(), HMMConvergenceWarning, stacklevel=3)
    return hmm, report


def train_mixsplit_many(
    sequences: Sequence[Sequence[np.ndarray]],
    n_states: int = TrainingConfig.n_states,
    n_mix: int = TrainingConfig.n_mix,
    *,
    n_iter: int = TrainingConfig.n_iter,
    tol: float = TrainingConfig.tol,
    covar_floor: float = COVAR_FLOOR,
    name: str | Sequence[str] = "",
    warn: bool = True,
) -> list[tuple[GestureHMM, TrainingReport, list[tuple[float, ...]]]]:
    """:func:`train_mixsplit` for many independent models, each stage's Baum–Welch batched.

    ``sequences``: one list of training sequences (T_i, D) per model; ``name`` one for all or one per
    model; the rest as :func:`train_mixsplit`. Every model goes through the same stages (M = 1 … n_mix),
    and each stage is one :func:`glu.gestures.baum_welch_batch.fit_many` over all models, equal to
    :func:`baum_welch` per model to rounding (tested). When Baum–Welch fails for some model, every model
    is retrained alone so the error names it.
    """
    from threadpoolctl import threadpool_limits

    from glu.gestures import baum_welch as bw
    from glu.gestures.baum_welch_batch import fit_many

    names = [name] * len(sequences) if isinstance(name, str) else list(name)
    if len(names) != len(sequences):
        raise ModelError(f"{len(sequences)} training sets need as many names, got {len(names)}")
    checked = [
        _checked(s, n_states, n_mix, n_iter, tol, covar_floor, nm)
        for s, nm in zip(sequences, names, strict=True)
    ]
    hmms = [flat_start(seqs, n_states, nm) for (seqs, _), nm in zip(checked, names, strict=True)]
    stages: list[list[tuple[float, ...]]] = [[] for _ in hmms]
    try:
        while True:
            problems = [
                (seqs, bw.GMMHMMParams(h.startprob, h.transmat, h.weights, h.means, h.covars))
                for (seqs, _), h in zip(checked, hmms, strict=True)
            ]
            with warnings.catch_warnings(), np.errstate(all="ignore"), threadpool_limits(1):
                warnings.simplefilter("ignore", RuntimeWarning)
                results = fit_many(
                    problems, n_iter, [tol * f for _, f in checked], covariance="ml", covar_floor=covar_floor
                )
            hmms = [GestureHMM(*r.params, name=nm) for r, nm in zip(results, names, strict=True)]
            for st, r in zip(stages, results, strict=True):
                st.append(tuple(float(h) for h in r.history))
            if hmms[0].n_mix >= n_mix:
                break
            hmms = [split_heaviest(h) for h in hmms]
    except (ValueError, np.linalg.LinAlgError, ModelError):  # say which model failed, as train_mixsplit does
        return [
            train_mixsplit(
                seqs, n_states, n_mix, n_iter=n_iter, tol=tol, covar_floor=covar_floor, name=nm, warn=warn
            )
            for (seqs, _), nm in zip(checked, names, strict=True)
        ]
    return [
        (*_finish(h, seqs, st, tol, n_iter, n_mix, nm, warn), st)
        for h, (seqs, _), st, nm in zip(hmms, checked, stages, names, strict=True)
    ]
