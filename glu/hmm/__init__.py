"""Gesture HMMs: left-to-right hidden Markov models with Gaussian-mixture emissions, one model family.

Laid out the way dynamax lays out a model family, one module per concern:

* :mod:`~glu.hmm.model` — :class:`GestureHMM`, one model's parameters, validated, and its JSON form;
* :mod:`~glu.hmm.inference` — the forward and forward–backward recursions as pure functions over arrays:
  the readable reference, the one to edit and the oracle the fast paths are tested against;
* :mod:`~glu.hmm.em` — Baum–Welch from sufficient statistics with a weight per sequence
  (:class:`SufficientStats`, :func:`expected_stats`, :func:`maximise`, :func:`fit`): the readable reference
  of EM;
* :mod:`~glu.hmm.scoring` — many sequences scored against many models (:func:`stack_models`,
  :func:`loglik_many`, :class:`BatchScorer`, frame by frame :class:`BankStream`);
* :mod:`~glu.hmm.online` — online stepwise EM (:class:`OnlineModels`), the E-step of one episode under
  many models (:func:`episode_stats`) and of many sequences under one (:func:`batch_stats`);
* :mod:`~glu.hmm.initialisation` — initial models: equal time slices and their Gaussian mixtures;
* :mod:`~glu.hmm.config` — :class:`TrainingConfig`, the one home of the training settings, and
  :class:`TrainingReport`;
* :mod:`~glu.hmm.glu_recipe` and :mod:`~glu.hmm.mixsplit` — glu's recipe and the originals';
* :mod:`~glu.hmm.training` — :func:`train`, the one entry point, for one model or many;
* :mod:`~glu.hmm.original` — the originals' 2013 models, imported from their ``.mat`` files.

The compiled fast paths live behind these, in the private :mod:`glu.hmm._engine`: the one batched,
weighted EM and its E-step (every trainer, online learning), the compiled recursions, the compiled loops
of the initial mixtures. Each is tested equal to the reference (to rounding). The recogniser — a bank of
these models over gesture features — is :class:`glu.gestures.Recognizer`.
"""

from glu.hmm.config import (
    RECIPES,
    HMMConvergenceWarning,
    TrainingConfig,
    TrainingReport,
)
from glu.hmm.em import GMMHMMParams, SufficientStats, expected_stats, fit, maximise
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
from glu.hmm.online import OnlineModels, batch_stats, episode_stats, first_model
from glu.hmm.original import load_original_hmms
from glu.hmm.scoring import Bank, BankStream, BatchScorer, loglik_many, params_bank, stack_models
from glu.hmm.training import Trained, train

__all__ = [
    "RECIPES",
    "Bank",
    "BankStream",
    "BatchScorer",
    "ForwardState",
    "GMMHMMParams",
    "GestureHMM",
    "HMMConvergenceWarning",
    "OnlineModels",
    "SufficientStats",
    "Trained",
    "TrainingConfig",
    "TrainingReport",
    "as_sequence",
    "batch_stats",
    "episode_stats",
    "expected_stats",
    "first_model",
    "fit",
    "forward_curve",
    "forward_step",
    "kmeans_labels",
    "left_to_right_transmat",
    "load_original_hmms",
    "log_emissions",
    "log_softmax",
    "loglik_many",
    "maximise",
    "p_hmm_from_loglik",
    "params_bank",
    "stack_models",
    "train",
]
