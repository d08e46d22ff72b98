"""Gesture HMMs: left-to-right hidden Markov models with Gaussian-mixture emissions, one model family.

Laid out the way dynamax lays out a model family, one module per concern:

* :mod:`~glu.hmm.model` — :class:`GestureHMM`, one model's parameters, validated, and its JSON form;
* :mod:`~glu.hmm.inference` — the forward and forward–backward recursions as pure functions over arrays:
  the readable reference, the one to edit and the oracle the fast paths are tested against;
* :mod:`~glu.hmm.em` — Baum–Welch, one model, built on those recursions; weighted EM from sufficient
  statistics (:class:`SufficientStats`, :func:`expected_stats`, :func:`maximise`, :func:`fit_weighted`), for
  uncertain labels and online learning;
* :mod:`~glu.hmm.initialisation` — initial models: equal time slices and their Gaussian mixtures;
* :mod:`~glu.hmm.config` — :class:`TrainingConfig`, the one home of the training settings, and
  :class:`TrainingReport`;
* :mod:`~glu.hmm.glu_recipe` and :mod:`~glu.hmm.mixsplit` — glu's recipe and the originals';
* :mod:`~glu.hmm.training` — :func:`train`, the one entry point, for one model or many;
* :mod:`~glu.hmm.original` — the originals' 2013 models, imported from their ``.mat`` files.

The fast paths live behind these, in the private :mod:`glu.hmm._engine`: compiled loops (numba), the
banked scoring of many sequences against many models (:class:`BatchScorer`, :func:`loglik_many`), batched
EM for many models at once, the compiled loops of the initial mixtures, and the E-step of one episode
under many models for online learning (:func:`episode_stats`, :func:`expected_stats_bank`,
:func:`loglik_bank`; :func:`expected_stats_fast` for many sequences under one model). Each is tested equal to
the reference (to rounding). The recogniser — a bank of these models over gesture features — is
:class:`glu.gestures.Recognizer`.
"""

from glu.hmm._engine.batch import Bank, BatchScorer, loglik_many, stack_models
from glu.hmm._engine.online import episode_stats, expected_stats_bank, expected_stats_fast, loglik_bank
from glu.hmm.config import (
    RECIPES,
    HMMConvergenceWarning,
    TrainingConfig,
    TrainingReport,
)
from glu.hmm.em import GMMHMMParams, SufficientStats, expected_stats, fit_weighted, maximise
from glu.hmm.inference import (
    ForwardState,
    forward_curve,
    forward_step,
    left_to_right_transmat,
    log_emissions,
    log_softmax,
    p_hmm_from_loglik,
)
from glu.hmm.initialisation import kmeans_labels
from glu.hmm.model import GestureHMM, as_sequence
from glu.hmm.original import load_original_hmms
from glu.hmm.training import Trained, train

__all__ = [
    "RECIPES",
    "Bank",
    "BatchScorer",
    "ForwardState",
    "GMMHMMParams",
    "GestureHMM",
    "HMMConvergenceWarning",
    "SufficientStats",
    "Trained",
    "TrainingConfig",
    "TrainingReport",
    "as_sequence",
    "episode_stats",
    "expected_stats",
    "expected_stats_bank",
    "expected_stats_fast",
    "fit_weighted",
    "forward_curve",
    "forward_step",
    "kmeans_labels",
    "left_to_right_transmat",
    "load_original_hmms",
    "log_emissions",
    "log_softmax",
    "loglik_bank",
    "loglik_many",
    "maximise",
    "p_hmm_from_loglik",
    "stack_models",
    "train",
]
