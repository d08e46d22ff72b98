"""The originals' HMM training recipe, "mixsplit": flat start, Baum–Welch, mixture splitting (docs/method.md
§5.1).

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
implies. :data:`~glu.hmm.config.COVAR_FLOOR` (``TrainingConfig.covar_floor``) reproduces it: covariances are
the maximum-likelihood ones plus ``covar_floor·I`` (``covar_floor = 0`` is plain maximum likelihood, for which
the log-likelihood never decreases within a stage). A component that loses all its frames keeps its previous
covariance.

glu's own recipe (:mod:`glu.hmm.glu_recipe`) starts instead from equal time slices of each sequence,
fits all M components of a slice at once (scikit-learn ``GaussianMixture``) and regularises covariances
with a weak inverse-Wishart prior; :data:`~glu.hmm.config.RECIPES` names both, ``TrainingConfig.recipe`` and
``glu hmm train --recipe`` choose. Baum–Welch is the same batched EM in both
(:func:`glu.hmm._engine.em_batch.fit_many`: ``ml`` covariances here, ``map`` in glu's).

Example
-------
>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> seqs = [np.cumsum(rng.normal(size=(40, 3)), axis=0) for _ in range(4)]
>>> from glu.hmm.config import TrainingConfig
>>> hmm, report, stages = train_one(seqs, TrainingConfig(n_states=3, n_mix=2, recipe="mixsplit"), name="tap")
>>> hmm.n_states, hmm.n_mix, len(stages), hmm.is_left_to_right
(3, 2, 2, True)
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

import numpy as np

from glu.errors import ModelError
from glu.hmm import em
from glu.hmm._engine.em_batch import fit_many
from glu.hmm.config import COVAR_FLOOR, TrainingConfig, TrainingReport, checked_sequences, make_report
from glu.hmm.inference import left_to_right_transmat
from glu.hmm.model import GestureHMM

SPLIT_OFFSET = 0.2
"""A split moves the two new means this many standard deviations (per coordinate) apart from the old one."""
FLAT_STAY = 0.5
"""Self-transition probability of the flat start."""


def flat_start(sequences: Sequence[np.ndarray], n_states: int, name: str = "") -> GestureHMM:
    """The flat-start model: every state one Gaussian with the global mean and covariance, 0.5 stay / 0.5
    next.

    ``sequences`` are arrays of shape (T_i, D); the covariance is the maximum-likelihood one of all their
    frames pooled (divided by the number of frames).
    """
    X = np.concatenate(sequences)
    D = X.shape[1]
    mean = X.mean(axis=0)
    cov = np.cov(X.T, bias=True).reshape(D, D)
    startprob = np.eye(n_states)[0]  # every sequence starts in the first state
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


def train_one(
    sequences: Sequence[np.ndarray], config: TrainingConfig, name: str = "", warn: bool = True
) -> tuple[GestureHMM, TrainingReport, list[tuple[float, ...]]]:
    """Train a left-to-right GMM-HMM by the originals' recipe: flat start, Baum–Welch, split, Baum–Welch, …

    Parameters
    ----------
    sequences : the training sequences, each an array of shape (T_i, D)
    config : Q and the final M (stages M = 1, 2, …, n_mix); per stage, at most ``n_iter`` Baum–Welch
        iterations, stopping when the log-likelihood gains less than ``tol`` per training frame;
        ``covar_floor`` is added to every re-estimated covariance (the originals': 0.01; 0: ML). The recipe
        is deterministic: it takes no seed, and ``covar_reg`` (glu's recipe) plays no part.
    name : the action (for messages)
    warn : emit an :class:`~glu.hmm.config.HMMConvergenceWarning` when the last stage did not converge

    Returns
    -------
    the model, a :class:`~glu.hmm.config.TrainingReport` of the last stage (``n_iter`` counts every
    stage's iterations), and the log-likelihood history of each stage (M = 1 first): :func:`train_batch`
    of one model. Call it through :func:`glu.hmm.train` (with ``TrainingConfig(recipe="mixsplit")``) unless
    you need the stages.
    """
    return train_batch([sequences], config, [name], warn)[0]


def _finish(
    hmm: GestureHMM,
    seqs: list[np.ndarray],
    stages: list[tuple[float, ...]],
    config: TrainingConfig,
    name: str,
    warn: bool,
) -> tuple[GestureHMM, TrainingReport]:
    final = float(sum(hmm.loglik(X) for X in seqs))
    n_run = sum(len(h) for h in stages)
    report = make_report(name, seqs, stages[-1], n_run, final, config.tol, config.n_iter * config.n_mix, warn)
    return hmm, report


def train_batch(
    sequences: Sequence[Sequence[np.ndarray]],
    config: TrainingConfig,
    names: Sequence[str],
    warn: bool = True,
    progress: Callable[[int], None] | None = None,
) -> list[tuple[GestureHMM, TrainingReport, list[tuple[float, ...]]]]:
    """The originals' recipe (see :func:`train_one`) for many independent models, each stage's Baum–Welch
    batched: the one training path of this recipe.

    ``sequences``: one list of training sequences (T_i, D) per model; ``names`` one per model. Every model
    goes through the same stages (M = 1 … n_mix), and each stage is one
    :func:`glu.hmm._engine.em_batch.fit_many` over all models (``ml`` covariances plus the floor), equal to
    :func:`glu.hmm.em.fit` per model to rounding (tested). When Baum–Welch fails for some model, every
    model is trained again alone so that the error names it. ``progress`` is called with the number of
    models that have just finished their last stage.
    """
    checked = [checked_sequences(s, config, nm) for s, nm in zip(sequences, names, strict=True)]
    hmms = [flat_start(seqs, config.n_states, nm) for (seqs, _), nm in zip(checked, names, strict=True)]
    stages: list[list[tuple[float, ...]]] = [[] for _ in hmms]
    try:
        while True:
            last = hmms[0].n_mix >= config.n_mix
            hmms = _stage(
                hmms,
                [seqs for seqs, _ in checked],
                (config.n_iter, config.tol, config.covar_floor),
                stages,
                progress if last else None,
            )
            if last:
                break
            hmms = [split_heaviest(h) for h in hmms]
    except ModelError:
        if len(hmms) == 1:
            raise
        return [
            train_batch([seqs], config, [nm], warn)[0] for (seqs, _), nm in zip(checked, names, strict=True)
        ]
    return [
        (*_finish(h, seqs, st, config, nm, warn), st)
        for h, (seqs, _), st, nm in zip(hmms, checked, stages, names, strict=True)
    ]


def baum_welch(
    hmm: GestureHMM,
    sequences: Sequence[np.ndarray],
    n_iter: int,
    tol: float,
    covar_floor: float = COVAR_FLOOR,
) -> tuple[GestureHMM, tuple[float, ...]]:
    """One stage of the recipe for one model: Baum–Welch from ``hmm``, every parameter re-estimated.

    Covariances are the maximum-likelihood ones (about the updated means, as the originals' toolbox
    computed them) plus ``covar_floor·I``; a component that lost its frames keeps its covariance. Stops
    after ``n_iter`` iterations or when the total log-likelihood gains less than ``tol`` × the number of
    frames. Returns the model and the total log-likelihood before each M-step.
    """
    stages: list[list[tuple[float, ...]]] = [[]]
    fitted = _stage([hmm], [list(sequences)], (n_iter, tol, covar_floor), stages, None)[0]
    return fitted, stages[0][0]


def _stage(
    hmms: list[GestureHMM],
    sequences: list[list[np.ndarray]],
    limits: tuple[int, float, float],
    stages: list[list[tuple[float, ...]]],
    progress: Callable[[int], None] | None,
) -> list[GestureHMM]:
    """:func:`baum_welch` of every model in one batch (:func:`~glu.hmm._engine.em_batch.fit_many`), with
    ``limits = (n_iter, tol, covar_floor)``; appends each model's history to ``stages``."""
    from threadpoolctl import threadpool_limits

    n_iter, tol, covar_floor = limits
    problems = [
        (seqs, em.GMMHMMParams(h.startprob, h.transmat, h.weights, h.means, h.covars))
        for seqs, h in zip(sequences, hmms, strict=True)
    ]
    tols = [tol * sum(len(X) for X in seqs) for seqs in sequences]
    who = hmms[0].name if len(hmms) == 1 else "one of the models"
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"), threadpool_limits(1):
            warnings.simplefilter("ignore", RuntimeWarning)
            results = fit_many(
                problems, n_iter, tols, covariance="ml", covar_floor=covar_floor, progress=progress
            )
    except (ValueError, np.linalg.LinAlgError) as e:
        raise ModelError(f"Baum–Welch failed for {who or 'the model'} at M = {hmms[0].n_mix}: {e}") from None
    out = []
    for h, r, st in zip(hmms, results, stages, strict=True):
        try:
            out.append(GestureHMM(*r.params, name=h.name))
        except ModelError as e:
            raise ModelError(
                f"Baum–Welch diverged for {h.name or 'the model'} at M = {h.n_mix} ({e}); try covar_floor > 0"
            ) from None
        st.append(tuple(float(x) for x in r.history))
    return out
