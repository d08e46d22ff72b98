"""One gesture HMM: a left-to-right hidden Markov model with Gaussian-mixture emissions.

The model of docs/method.md §1.2: for each action ``a`` a left-to-right HMM with ``Q`` states whose emissions
are mixtures of ``M`` full-covariance Gaussians over the ``D = 3`` hand features
(:mod:`glu.gestures.features`). :class:`GestureHMM` holds one model's parameters (immutable, validated)
with the Cholesky factors precomputed, and scores sequences with the pure functions of
:mod:`glu.hmm.inference`: ``log L(G_1^t | a)`` for every prefix in one pass.

Training is in :mod:`glu.hmm.training`, the bank of models and its streaming form in
:mod:`glu.gestures.recognizer`, the originals' 2013 models in :mod:`glu.hmm.original`.

Example
-------
>>> import numpy as np
>>> from glu.hmm.inference import left_to_right_transmat
>>> hmm = GestureHMM(
...     startprob=[1.0, 0.0], transmat=left_to_right_transmat(2, 0.9), weights=[[1.0], [1.0]],
...     means=[[[0.0, 0.0, 0.0]], [[1.0, 1.0, 1.0]]], covars=np.tile(np.eye(3), (2, 1, 1, 1)), name="tap")
>>> hmm.n_states, hmm.n_mix, hmm.n_features
(2, 1, 3)
>>> X = np.linspace(0, 1, 10)[:, None].repeat(3, axis=1)        # (T=10, D=3)
>>> round(hmm.loglik(X), 4)
-29.9073
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from glu.errors import DataError, ModelError
from glu.hmm.inference import forward_curve, gaussian_factors, log_emissions


def as_sequence(X: Any, n_features: int, what: str = "sequence") -> np.ndarray:
    """``X`` as a float array of shape (n_frames, n_features) with at least one frame, all finite."""
    try:
        X = np.asarray(X, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"{what}: not an array of numbers") from None
    if X.ndim != 2 or X.shape[1] != n_features:
        raise DataError(f"{what}: expected shape (n_frames, {n_features}), got {X.shape}")
    if len(X) == 0:
        raise DataError(f"{what}: no frames")
    if not np.all(np.isfinite(X)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(X), axis=1))[0])
        raise DataError(f"{what}: frame {bad + 1} (1-based) is not finite")
    return X


MAX_MEAN = 1e6
"""The largest magnitude of an HMM mean glu accepts (features are hand positions in body sizes, of
order 1)."""
MAX_COVAR = 1e12
"""The largest magnitude of a covariance entry glu accepts."""


@dataclass(frozen=True, eq=False)
class GestureHMM:
    """A left-to-right HMM with Gaussian-mixture emissions (parameters only; immutable).

    Attributes
    ----------
    startprob : array, shape (Q,)
    transmat : array, shape (Q, Q), rows sum to one
    weights : array, shape (Q, M), mixture weights, rows sum to one
    means : array, shape (Q, M, D)
    covars : array, shape (Q, M, D, D), full covariances (positive definite where the weight is > 0)
    name : the action it models
    chol_inv : array, shape (Q, M, D, D) — the inverse Cholesky factors of the covariances (derived)
    log_norm : array, shape (Q, M) — ``log w − (D/2) log 2π − log |L|`` of each component (derived; −∞ for
        weight 0): with ``chol_inv``, what :func:`~glu.hmm.inference.log_emissions` takes
    """

    startprob: np.ndarray
    transmat: np.ndarray
    weights: np.ndarray
    means: np.ndarray
    covars: np.ndarray
    name: str = ""
    chol_inv: np.ndarray = field(init=False, repr=False)
    log_norm: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        who = f"HMM {self.name!r}" if self.name else "HMM"
        arrs = {}
        for k in ("startprob", "transmat", "weights", "means", "covars"):
            try:
                a = np.array(getattr(self, k), dtype=float)
            except (TypeError, ValueError):
                raise ModelError(f"{who}: {k} is not an array of numbers") from None
            if not np.all(np.isfinite(a)):
                raise ModelError(f"{who}: {k} has non-finite values")
            arrs[k] = a
        if arrs["means"].ndim != 3:
            raise ModelError(f"{who}: means must have shape (Q, M, D), got {arrs['means'].shape}")
        Q, M, D = arrs["means"].shape
        shapes = {"startprob": (Q,), "transmat": (Q, Q), "weights": (Q, M), "covars": (Q, M, D, D)}
        for k, s in shapes.items():
            if arrs[k].shape != s:
                raise ModelError(f"{who}: {k} must have shape {s} (Q={Q}, M={M}, D={D}), got {arrs[k].shape}")
        for k, axis in (("startprob", 0), ("transmat", 1), ("weights", 1)):
            a = arrs[k]
            if np.any(a < 0) or not np.allclose(a.sum(axis=axis), 1.0, rtol=0, atol=1e-6):
                raise ModelError(f"{who}: {k} must be non-negative and sum to one (along axis {axis})")
        for k, bound in (("means", MAX_MEAN), ("covars", MAX_COVAR)):  # beyond: scores overflow to -inf, nan
            if np.abs(arrs[k]).max(initial=0.0) > bound:
                raise ModelError(
                    f"{who}: {k} as large as {np.abs(arrs[k]).max():.3g}; at most {bound:g} in magnitude "
                    "(features are positions in body sizes: such a model gives no finite likelihood)"
                )
        cov = arrs["covars"]
        if not np.allclose(cov, np.swapaxes(cov, -1, -2), rtol=1e-8, atol=1e-12):
            raise ModelError(f"{who}: covariances must be symmetric")
        try:
            chol_inv, log_norm = gaussian_factors(arrs["weights"], cov)
        except np.linalg.LinAlgError:
            raise ModelError(f"{who}: a covariance matrix is not positive definite") from None
        for k, a in arrs.items():
            a.flags.writeable = False
            object.__setattr__(self, k, a)
        object.__setattr__(self, "chol_inv", chol_inv)
        object.__setattr__(self, "log_norm", log_norm)

    @property
    def n_states(self) -> int:
        """Q."""
        return self.means.shape[0]

    @property
    def n_mix(self) -> int:
        """M."""
        return self.means.shape[1]

    @property
    def n_features(self) -> int:
        """D."""
        return self.means.shape[2]

    @property
    def is_left_to_right(self) -> bool:
        """True if no transition goes to an earlier state (transmat is upper triangular)."""
        return bool(np.all(np.tril(self.transmat, -1) == 0))

    def log_emission(self, X: np.ndarray) -> np.ndarray:
        """Emission log-densities ``log p(x_t | q)``, shape (T, Q), for a sequence of shape (T, D)."""
        return log_emissions(as_sequence(X, self.n_features), self.means, self.chol_inv, self.log_norm)

    def loglik_curve(self, X: np.ndarray) -> np.ndarray:
        """``log L(G_1^t | model)`` for every prefix t = 1 … T, shape (T,), of a sequence of shape (T, D)."""
        return forward_curve(self.log_emission(X), self.startprob, self.transmat)

    def loglik(self, X: np.ndarray) -> float:
        """``log L(G | model)`` of a sequence of shape (T, D), by the forward algorithm."""
        return float(self.loglik_curve(X)[-1])

    def to_dict(self) -> dict[str, Any]:
        """The parameters as nested lists (the ``models`` entries of the recogniser file)."""
        return {
            "n_states": self.n_states,
            "n_mix": self.n_mix,
            "n_features": self.n_features,
            "startprob": self.startprob.tolist(),
            "transmat": self.transmat.tolist(),
            "weights": self.weights.tolist(),
            "means": self.means.tolist(),
            "covars": self.covars.tolist(),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], name: str = "") -> GestureHMM:
        """A model from :meth:`to_dict` output; raises :class:`ModelError` if malformed."""
        try:
            return cls(d["startprob"], d["transmat"], d["weights"], d["means"], d["covars"], name=name)
        except (KeyError, TypeError) as e:
            raise ModelError(f"HMM {name!r}: missing or malformed field {e}") from None

    def sample(self, n_frames: int, seed: int) -> np.ndarray:
        """A sequence of ``n_frames`` frames drawn from the model, shape (n_frames, D).

        The draws are hmmlearn's ``GMMHMM.sample(n_frames, random_state=seed)``'s, in its order (a
        ``RandomState(seed)``: the first state by the start distribution's cumulative sum, then per frame a
        component by its weight and a multivariate normal, then the next state), so the same seed gives the
        same sequence (``tests/library/test_hmm.py``).
        """
        rs = np.random.RandomState(seed)
        start_cdf, trans_cdf = np.cumsum(self.startprob), np.cumsum(self.transmat, axis=1)
        state = int((start_cdf > rs.rand()).argmax())
        frames = []
        for t in range(n_frames):
            if t:
                state = int((trans_cdf[state] > rs.rand()).argmax())
            m = rs.choice(self.n_mix, p=self.weights[state])
            frames.append(rs.multivariate_normal(self.means[state, m], self.covars[state, m]))
        return np.atleast_2d(frames)
