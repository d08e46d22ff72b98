"""Online stepwise EM: gesture HMMs that learn one episode at a time.

A robot that updates its gesture models after each episode keeps, per model, the running mean of the
sufficient statistics of what it has seen (:class:`~glu.hmm.em.SufficientStats`) and re-estimates the model
from them after every episode: stepwise EM (Cappé & Moulines 2009; Liang & Klein 2009). For an episode of
label weight ``w`` the statistics move by

    ``s ← (1 − η) s + η s_episode``,  ``η = w / W^α``,

``W`` the model's label weight so far, and the model is :func:`~glu.hmm.em.maximise` of ``W · s``. With
``α = 1`` this is the plain accumulation ``Σ w s_episode`` (batch EM's statistics, one E-step late);
``α < 1`` forgets the early episodes faster (``α`` in (0.5, 1] for convergence).

* :class:`OnlineModels` — many models learnt side by side, stacked over leading axes (say learner ×
  action): their parameters, running statistics and label weights; :meth:`~OnlineModels.estep` runs one
  episode under any of them at once, :meth:`~OnlineModels.update` makes the stepwise step and the M-step,
  :meth:`~OnlineModels.start` sets a first model (:func:`first_model`: weighted EM on a few episodes);
* :func:`episode_stats` — the E-step of one sequence under many models, and :func:`batch_stats` — many
  sequences under one model: both the compiled E-step of :mod:`glu.hmm._engine.em_batch`, equal to
  :func:`glu.hmm.em.expected_stats` to rounding (``tests/library/test_weighted_em.py``).

Which episodes a model learns from, and with what weight, is the study's business
(:mod:`glu.studies.learning.online`: labelling schemes, buffers, clustering, checkpoints).

Example
-------
>>> import numpy as np
>>> from glu.hmm.config import TrainingConfig
>>> rng = np.random.default_rng(0)
>>> episodes = [np.cumsum(rng.normal(size=(30, 2)), axis=0) for _ in range(6)]
>>> config = TrainingConfig(n_states=3, n_mix=1, n_iter=5)
>>> models = OnlineModels.empty((2,), config, n_features=2)          # two models, none trained yet
>>> models.start(0, *first_model(episodes[:3], np.ones(3), config))
>>> stats, loglik = models.estep(episodes[3], np.array([0]))
>>> models.update(np.array([0]), stats, np.array([1.0]), config.covar_reg)
>>> float(models.total[0]), bool(models.exists[1])
(4.0, False)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from glu.hmm._engine.em_batch import expected_stats_many
from glu.hmm.config import TrainingConfig
from glu.hmm.em import GMMHMMParams, SufficientStats, maximise, sequence_weights
from glu.hmm.scoring import loglik_many, params_bank
from glu.hmm.training import train

Index = tuple[np.ndarray, ...] | np.ndarray | int | tuple[int, ...]
"""Which models: any numpy index into the leading axes (a tuple of integer arrays picks many)."""


def episode_stats(
    X: np.ndarray, params: GMMHMMParams, weights: np.ndarray | None = None
) -> tuple[SufficientStats, np.ndarray]:
    """The E-step of one sequence under each of ``K`` models at once.

    Parameters
    ----------
    X : array, shape (T, D) — the sequence
    params : the models' parameters stacked: startprob (K, Q), transmat (K, Q, Q), weights (K, Q, M),
        means (K, Q, M, D), covars (K, Q, M, D, D)
    weights : array, shape (K,) — the sequence's weight for each model (default all 1); a model of weight 0
        gets exactly zero statistics, even one to which the sequence is impossible

    Returns
    -------
    the :class:`~glu.hmm.em.SufficientStats` of each model, batch shape (K,) (each equal to
    ``expected_stats([X], model_k, [w_k])`` to rounding), and ``log L(X | model)``, shape (K,) (unweighted)
    """
    X = np.asarray(X, dtype=float)
    K = params.means.shape[0]
    stats, loglik = expected_stats_many([[X]] * K, params, [np.ones(1)] * K)
    w = np.ones(K) if weights is None else np.asarray(weights, dtype=float)
    scaled = []
    for a in (stats.start, stats.trans, stats.counts, stats.first, stats.second, stats.loglik):
        wk = w.reshape(w.shape + (1,) * (a.ndim - 1))
        with np.errstate(invalid="ignore"):
            scaled.append(np.where(wk > 0, wk * a, 0.0))
    return SufficientStats(*scaled, w.copy(), w * stats.frames), loglik


def batch_stats(
    sequences: Sequence[np.ndarray], params: GMMHMMParams, weights: Sequence[float] | np.ndarray | None = None
) -> SufficientStats:
    """The E-step of many sequences (shapes (T_i, D)) under one model, each times its weight (default 1):
    :func:`glu.hmm.em.expected_stats`, compiled (equal to it to rounding)."""
    w = sequence_weights(sequences, weights)
    if not np.any(w > 0):
        return SufficientStats.zeros(*params.means.shape)
    stacked = GMMHMMParams(*(np.asarray(a, dtype=float)[None] for a in params))
    stats, _ = expected_stats_many([sequences], stacked, [w])
    return stats.take(0)


def first_model(
    sequences: Sequence[np.ndarray], weights: np.ndarray, config: TrainingConfig, seed: int = 0
) -> tuple[GMMHMMParams, SufficientStats]:
    """A first model from a few weighted sequences (:func:`glu.hmm.train` with ``weights``: glu's recipe,
    ``config.n_iter`` EM iterations), and the statistics of those sequences under it.

    ``sequences``: S arrays, each of shape (T_i, D); ``weights``, shape (S,). Returns one model's parameters
    (startprob (Q,), transmat (Q, Q), weights (Q, M), means (Q, M, D), covars (Q, M, D, D)) and the
    sequences' weighted statistics under it (:func:`batch_stats`, no batch axis).
    """
    model = train(list(sequences), config, weights=weights, seed=seed, warn=False).model
    params = GMMHMMParams(model.startprob, model.transmat, model.weights, model.means, model.covars)
    return params, batch_stats(sequences, params, weights)


def step_size(total: np.ndarray, weight: np.ndarray, step: float) -> np.ndarray:
    """``η = w / W^α`` of the stepwise-EM step (at most 1), for the label weight ``W`` after the episode.

    ``total`` (W) and ``weight`` (w): arrays of one shape, one entry per model (e.g. (n,)); η has that shape.
    """
    return np.minimum(1.0, weight / np.asarray(total, dtype=float) ** step)


@dataclass
class OnlineModels:
    """Models learnt online, stacked over leading axes ``B`` (say learner × action).

    Attributes
    ----------
    params : the models' parameters, each array with leading axes ``B`` (placeholders where no model exists)
    mean : the running mean of each model's statistics (:class:`~glu.hmm.em.SufficientStats`, batch ``B``)
    total : array, shape ``B`` — each model's label weight so far, ``W``
    exists : bool array, shape ``B`` — which models have been started
    step : ``α`` of the step size ``η = w / W^α``, in (0.5, 1]; 1 accumulates
    """

    params: GMMHMMParams
    mean: SufficientStats
    total: np.ndarray
    exists: np.ndarray
    step: float = 1.0

    @classmethod
    def empty(
        cls, shape: tuple[int, ...], config: TrainingConfig, n_features: int, step: float = 1.0
    ) -> OnlineModels:
        """``shape`` models of ``config``'s size over ``n_features`` features, none started yet."""
        Q, M, D = config.n_states, config.n_mix, n_features
        params = GMMHMMParams(
            np.zeros(shape + (Q,)),
            np.zeros(shape + (Q, Q)),
            np.full(shape + (Q, M), 1.0 / M),
            np.zeros(shape + (Q, M, D)),
            np.broadcast_to(np.eye(D), shape + (Q, M, D, D)).copy(),
        )
        return cls(
            params, SufficientStats.zeros(Q, M, D, shape), np.zeros(shape), np.zeros(shape, bool), step
        )

    def models(self, idx: Index) -> GMMHMMParams:
        """The parameters of the models at ``idx``."""
        return GMMHMMParams(*(a[idx] for a in self.params))

    def start(self, idx: Index, params: GMMHMMParams, stats: SufficientStats) -> None:
        """Start the model at ``idx`` from ``params`` and the statistics of what it was trained on (their
        weight becomes its label weight; see :func:`first_model`)."""
        for a, b in zip(self.params, params, strict=True):
            a[idx] = b
        self.mean.put(idx, stats.scaled(1.0 / float(stats.weight)))
        self.total[idx] = float(stats.weight)
        self.exists[idx] = True

    def estep(self, X: np.ndarray, idx: Index) -> tuple[SufficientStats, np.ndarray]:
        """The E-step of one episode (shape (T, D)) under each model at ``idx``: the unweighted statistics
        (batch shape of ``idx``) and ``log L(X | model)`` (:func:`episode_stats`)."""
        return episode_stats(X, self.models(idx))

    def update(self, idx: Index, stats: SufficientStats, weights: np.ndarray, covar_reg: float) -> None:
        """The stepwise-EM step and the M-step of the models at ``idx``.

        ``stats`` are the unweighted statistics of one episode under each of them (:meth:`estep`; batch
        shape: that of the selection, say (n,)) and ``weights``, shape (n,), its label weight for each
        (> 0); each running mean moves by ``η`` towards the episode's statistics and each model becomes
        ``maximise(W · s)`` (glu's ``map`` covariance with ``covar_reg``).
        """
        w = np.asarray(weights, dtype=float)
        total = self.total[idx] + w
        eta = step_size(total, w, self.step)
        mean = self.mean.take(idx).scaled(1.0 - eta) + stats.scaled(eta)
        self.mean.put(idx, mean)
        self.total[idx] = total
        new = maximise(mean.scaled(total), self.models(idx), covar_reg, "map")
        for a, b in zip(self.params, new, strict=True):
            a[idx] = b

    def loglik(self, sequences: Sequence[np.ndarray], idx: Index) -> np.ndarray:
        """``log L(G_s | model)`` of every sequence under every model at ``idx`` (a flat selection, such as
        a tuple of index arrays; the models must exist), shape (S, n)
        (:func:`glu.hmm.scoring.loglik_many`)."""
        return loglik_many(params_bank(self.models(idx)), list(sequences))
