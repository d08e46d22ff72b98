"""How gesture HMMs are trained, and what happened: the one home of the training settings.

* :class:`TrainingConfig` holds every setting (Q = 6 states, M = 3 Gaussians, the originals' model size; EM
  limits; the recipe and its regulariser). The command line, the experiments, the sweeps and the notebooks
  build one and pass it whole to :func:`glu.hmm.train`.
* :class:`TrainingReport` says how EM went for one model; :class:`HMMConvergenceWarning` is raised when it
  did not converge.
* :func:`checked_sequences` validates training data the same way for every recipe.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from glu.errors import DataError, ModelError
from glu.hmm.model import as_sequence

RECIPES: tuple[str, ...] = ("glu", "mixsplit")
"""How gesture HMMs can be trained: ``glu`` (:mod:`glu.hmm.glu_recipe`) or ``mixsplit`` (the originals',
:mod:`glu.hmm.mixsplit`)."""
COVAR_FLOOR = 0.01
"""The mixsplit recipe adds this to every re-estimated covariance (times the identity), as the originals'
toolbox did (in the units of the original models: the logged coordinates / 1000)."""


def _is_int(x: Any) -> bool:
    return isinstance(x, numbers.Integral) and not isinstance(x, bool)


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
    covar_reg : (glu's recipe) strength of the weak inverse-Wishart prior on each covariance, a pseudo-scatter
        ``covar_reg·I`` (feature units², so 0.03 is a prior spread of about 0.17 units, 5 cm). The default was
        set while the real seated taps were in view; notebook 10 chooses it (with the feature set) by nested
        cross-validation on the standing segments only, and reports the outer accuracy
        (``docs/correspondence.md``)
    recipe : ``"glu"`` (time slices, mixtures fitted per slice, MAP EM: :mod:`glu.hmm.glu_recipe`) or
        ``"mixsplit"`` (the originals': flat start and mixture splitting, :mod:`glu.hmm.mixsplit`)
    covar_floor : (mixsplit) added to every re-estimated covariance, times the identity (the originals'
        0.01; 0 is plain maximum likelihood)
    """

    n_states: int = 6
    n_mix: int = 3
    n_iter: int = 200
    tol: float = 1e-4
    covar_reg: float = 0.03
    recipe: str = "glu"
    covar_floor: float = COVAR_FLOOR

    def __post_init__(self) -> None:
        if self.recipe not in RECIPES:
            raise ModelError(f"unknown training recipe {self.recipe!r}; allowed: {', '.join(RECIPES)}")
        if not (_is_int(self.n_states) and _is_int(self.n_mix)) or self.n_states < 1 or self.n_mix < 1:
            raise ModelError(f"n_states={self.n_states} and n_mix={self.n_mix} must be whole numbers ≥ 1")
        if not _is_int(self.n_iter) or self.n_iter < 1 or not self.tol > 0:
            raise ModelError(f"n_iter={self.n_iter} must be ≥ 1 and tol={self.tol} > 0")
        if not (self.covar_reg >= 0 and self.covar_floor >= 0):
            raise ModelError(f"covar_reg={self.covar_reg} and covar_floor={self.covar_floor} must be ≥ 0")

    def replace(self, **changes: Any) -> TrainingConfig:
        """A copy with ``changes`` (checked like the constructor's arguments)."""
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict[str, Any]:
        """The settings as a plain dict (a recogniser file's ``config``)."""
        return dataclasses.asdict(self)


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


def checked_sequences(
    sequences: Sequence[Any], config: TrainingConfig, name: str = ""
) -> tuple[list[np.ndarray], int]:
    """The training sequences as float arrays of shape (T_i, D) and their number of frames, or a clear error.

    Raises :class:`~glu.errors.DataError` for no sequences, a sequence of the wrong shape or with a frame
    that is not finite, or fewer frames than ``n_states × n_mix``.
    """
    who = f"training data for {name!r}" if name else "training data"
    if len(sequences) == 0:
        raise DataError(f"{who}: no sequences")
    first = np.asarray(sequences[0])
    D = first.shape[-1] if first.ndim == 2 else 3
    seqs = [as_sequence(X, D, f"{who}, sequence {i + 1}") for i, X in enumerate(sequences)]
    n_frames = sum(len(X) for X in seqs)
    if n_frames < config.n_states * config.n_mix:
        raise DataError(
            f"{who}: {n_frames} frames are too few for {config.n_states} states × {config.n_mix} mixtures"
        )
    return seqs, n_frames


def make_report(
    name: str,
    seqs: Sequence[np.ndarray],
    history: tuple[float, ...],
    n_iter_run: int,
    final_loglik: float,
    tol: float,
    max_iter: int,
    warn: bool,
    weighted_frames: float | None = None,
) -> TrainingReport:
    """The :class:`TrainingReport` of a fitted model (converged: the last change of the total
    log-likelihood below ``tol`` per frame, or per weighted frame with sequence weights,
    ``weighted_frames``); warns with :class:`HMMConvergenceWarning` when it did not.

    ``seqs``: the training sequences, each of shape (T_i, D) (only their lengths are read); ``history`` and
    ``final_loglik``: total training log-likelihoods (:class:`TrainingReport`).
    """
    n_frames = sum(len(X) for X in seqs)
    delta = history[-1] - history[-2] if len(history) >= 2 else math.inf
    converged = bool(abs(delta) < tol * (n_frames if weighted_frames is None else weighted_frames))
    report = TrainingReport(
        name, len(seqs), n_frames, n_iter_run, converged, history, final_loglik, tol, max_iter
    )
    if not converged and warn:
        warnings.warn(report.describe(), HMMConvergenceWarning, stacklevel=4)
    return report
