"""hmmlearn as the independent reference of glu's HMMs (tests only: hmmlearn is a test dependency).

* :func:`to_hmmlearn` — a :class:`~glu.hmm.model.GestureHMM` as hmmlearn's ``GMMHMM`` (for ``score`` and
  ``sample``);
* :func:`train_hmmlearn` — Baum–Welch by hmmlearn's ``GMMHMM.fit`` from given parameters, with glu's
  covariance prior (hmmlearn takes each component's scatter about the means *before* the update);
* :func:`fit_hmmlearn_update` — glu's reference E-step (:func:`glu.hmm.em.expected_stats`) followed by
  hmmlearn's M-step: the same scatter about the old means. Equal to :func:`train_hmmlearn` to rounding, so
  it checks glu's E-step (and the rest of the M-step) against hmmlearn's code.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from glu.hmm.em import FitResult, GMMHMMParams, expected_stats, maximise, scatter
from glu.hmm.model import GestureHMM


def to_hmmlearn(model: GestureHMM) -> Any:
    """An equivalent ``hmmlearn.hmm.GMMHMM``."""
    from hmmlearn.hmm import GMMHMM

    m = GMMHMM(n_components=model.n_states, n_mix=model.n_mix, covariance_type="full", init_params="")
    m.n_features = model.n_features
    m.startprob_, m.transmat_ = model.startprob.copy(), model.transmat.copy()
    m.weights_, m.means_, m.covars_ = model.weights.copy(), model.means.copy(), model.covars.copy()
    return m


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


def train_hmmlearn(
    sequences: list[np.ndarray],
    start: GMMHMMParams,
    n_iter: int,
    tol_total: float,
    covar_reg: float,
    seed: int = 0,
) -> FitResult:
    """hmmlearn's ``GMMHMM.fit`` from ``start`` (its ``tol`` on the total log-likelihood), with the
    covariance prior ``covar_reg·I`` as glu's ``map`` update; the fitted parameters and the history."""
    D = sequences[0].shape[1]
    n_states, n_mix = start.weights.shape
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
    model.startprob_, model.transmat_, model.weights_, model.means_, model.covars_ = (
        np.array(a, dtype=float) for a in start
    )
    hmm_log = logging.getLogger("hmmlearn.base")
    level = hmm_log.level
    hmm_log.setLevel(logging.ERROR)  # the tests read convergence from the history
    try:  # one BLAS thread: hmmlearn's many tiny products are several times slower with thread hand-offs
        with threadpool_limits(1):
            model.fit(np.concatenate(sequences), [len(X) for X in sequences])
    finally:
        hmm_log.setLevel(level)
    params = GMMHMMParams(model.startprob_, model.transmat_, model.weights_, model.means_, model.covars_)
    return FitResult(params, np.array(model.monitor_.history))


def fit_hmmlearn_update(
    sequences: list[np.ndarray], init: GMMHMMParams, n_iter: int, tol: float, covar_reg: float
) -> FitResult:
    """EM with glu's reference E-step and hmmlearn 0.3's M-step: glu's ``map`` update, except that each
    covariance is ``(S_old + r·I) / (N + 1)`` with the scatter about the means before the update."""
    params = GMMHMMParams(*(np.array(a, dtype=float) for a in init))
    D = params.means.shape[-1]
    history: list[float] = []
    for _ in range(n_iter):
        stats = expected_stats(sequences, params, None)
        history.append(float(stats.loglik))
        new = maximise(stats, params, covar_reg, "map")
        n = stats.counts[..., None, None]
        covars = (covar_reg * np.eye(D) + scatter(stats, params.means)) / (n + 1.0)
        params = new._replace(covars=0.5 * (covars + np.swapaxes(covars, -1, -2)))
        if len(history) >= 2 and history[-1] - history[-2] < tol:
            break
    return FitResult(params, np.array(history))
