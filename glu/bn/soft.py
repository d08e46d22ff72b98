"""Soft evidence on a network node, written once: the two rules as pure array functions.

A soft observation of a node X is a distribution ``q`` over its values (for Action: the gesture HMMs'
posterior ``p_HMM(A | G)``). It enters the network by one of two rules (docs/method.md §2.2):

``virtual``
    virtual (likelihood) evidence, ``p(Y | e) ∝ Σ_x p(Y, x | e) q(x)`` — the originals' soft fusion: ``q``
    is a likelihood ``λ(x) = q(x)`` (:func:`virtual_likelihood`);
``jeffrey``
    Jeffrey's rule, which makes the posterior marginal of X equal to ``q``:
    ``p(Y | e) = Σ_x p(Y | e, x) q(x)``: the likelihood ``λ(x) = q(x) / p(x | e)``
    (:func:`jeffrey_likelihood`; on several nodes, iterative proportional fitting, :func:`fit_jeffrey`).

Every engine receives soft evidence as likelihoods made here, one row per evidence set (a single query is a
batch of one row); :func:`soft_posterior` is the soft node's own posterior under each rule in closed form
(the fusion rules' tables, :mod:`glu.fusion`, use it).

>>> import numpy as np
>>> virtual_likelihood(np.array([[0.2, 0.6, 0.2]]))            # scaled so the largest entry is 1
array([[0.33333333, 1.        , 0.33333333]])
>>> lik, ok = jeffrey_likelihood(np.array([[0.5, 0.5]]), np.array([[0.8, 0.2]]))
>>> lik.round(3), ok                                               # q / p, largest entry 1
(array([[0.25, 1.  ]]), array([ True]))
>>> soft_posterior(np.array([0.8, 0.2]), np.array([0.5, 0.5]), "virtual")
array([0.8, 0.2])
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Literal

import numpy as np

from glu.errors import EvidenceError

SoftRule = Literal["virtual", "jeffrey"]
SOFT_RULES: tuple[str, ...] = ("virtual", "jeffrey")
"""The soft-evidence rules, the originals' first."""
SUM_TOL = 1e-6
"""A soft distribution must sum to 1 within this."""
IPFP_TOL, IPFP_MAX_ITER = 1e-13, 10_000
"""Jeffrey's rule on several nodes: iterate until every marginal is within ``IPFP_TOL`` of its ``q``."""


def check_soft_rule(rule: str) -> str:
    """``rule`` if it is one of :data:`SOFT_RULES`, else :class:`EvidenceError` naming the allowed ones."""
    if rule not in SOFT_RULES:
        raise EvidenceError(f"unknown soft rule {rule!r}; allowed: {', '.join(SOFT_RULES)}")
    return rule


def check_distribution(node: str, values: Sequence[str], q: np.ndarray) -> np.ndarray:
    """``q`` (shape (k,) for the node's k values) normalised to sum 1, or :class:`EvidenceError` naming the
    node and its values when it is not a distribution (negative, above 1, not finite, or a sum off 1)."""
    # an entry above 1 is refused before the sum, which could overflow (1e308 + 1e308)
    if (
        not np.all(np.isfinite(q))
        or (q < 0).any()
        or (q > 1.0 + SUM_TOL).any()
        or abs(q.sum() - 1.0) > SUM_TOL
    ):
        shown = ", ".join(f"{v}:{p:g}" for v, p in zip(values, q, strict=True))
        raise EvidenceError(
            f"soft evidence on {node} is not a distribution over its values ({shown}): "
            "entries must be non-negative and sum to 1"
        )
    return q / q.sum()


def virtual_likelihood(q: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
    """Virtual evidence as a likelihood: ``q`` scaled so that each row's largest entry is 1, shape (rows, k).

    A likelihood is defined up to a factor; scaling keeps tiny but valid likelihoods (1e-320) from
    underflowing. With ``allowed`` (bool, shape (rows, k): the values the other evidence leaves possible),
    entries elsewhere are set to 0 and the scale is taken over the allowed values only.
    """
    if allowed is not None:
        q = np.where(allowed, q, 0.0)
    top = q.max(axis=-1, keepdims=True)
    return q / np.where(top > 0, top, 1.0)


def jeffrey_likelihood(q: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The likelihood that turns the marginal ``p`` of a node into ``q`` (Jeffrey's rule): ``λ = q / p``.

    Parameters
    ----------
    q : array, shape (rows, k) — the wanted marginal
    p : array, shape (rows, k) — the node's marginal given the other evidence (NaN or 0 rows: impossible)

    Returns
    -------
    (λ scaled to a largest entry of 1 per row, shape (rows, k); ok, shape (rows,): False where ``q`` puts
    mass on a value that ``p`` excludes — evidence of probability 0)
    """
    p = np.where(np.isnan(p), 0.0, p)
    ok = ~((p <= 0) & (q > 0)).any(axis=-1) & (p.sum(axis=-1) > 0)
    lik = np.divide(q, p, out=np.zeros(np.broadcast_shapes(q.shape, p.shape)), where=p > 0)
    return virtual_likelihood(lik), ok


Marginal = Callable[[int, Mapping[int, np.ndarray]], np.ndarray]
"""``marginal(v, likelihoods)``: the marginal of node ``v`` given the hard evidence and the likelihoods of the
other soft nodes, shape (rows, k) (NaN rows: impossible)."""


def fit_jeffrey(
    soft: Mapping[int, np.ndarray], marginal: Marginal
) -> tuple[dict[int, np.ndarray], np.ndarray]:
    """Likelihoods that give every soft node its marginal ``q`` at once (Jeffrey's rule).

    One node: ``λ = q / p(x | other evidence)``. Several: iterative proportional fitting — each node's
    likelihood is corrected in turn by ``q / (its current marginal)`` until every marginal is within
    :data:`IPFP_TOL` of its ``q`` (at most :data:`IPFP_MAX_ITER` sweeps).

    Parameters
    ----------
    soft : node → q, shape (rows, k)
    marginal : see :data:`Marginal` (the engine's arithmetic)

    Returns
    -------
    (node → λ, shape (rows, k); ok, shape (rows,): False where the evidence is impossible)
    """
    rows = len(next(iter(soft.values())))
    lik = {v: np.ones_like(q) for v, q in soft.items()}
    ok = np.ones(rows, dtype=bool)
    for _ in range(IPFP_MAX_ITER if len(soft) > 1 else 1):
        worst = 0.0
        for v, q in soft.items():
            z = marginal(v, lik)
            z = np.where(np.isnan(z), 0.0, z)
            if len(soft) > 1:
                worst = max(worst, float(np.max(np.where(ok[:, None], np.abs(z - q), 0.0), initial=0.0)))
            step, fine = jeffrey_likelihood(q, z)
            ok &= fine
            lik[v] = virtual_likelihood(lik[v] * step)
        if worst < IPFP_TOL:
            break
    return lik, ok


def soft_posterior(p: np.ndarray, q: np.ndarray, rule: str) -> np.ndarray:
    """The soft node's own posterior under ``rule``, in closed form, vectorised over leading axes.

    ``virtual``: ``p · q`` normalised (the product rule); ``jeffrey``: ``q`` itself, restricted to the values
    that ``p`` (the node's marginal given the other evidence, shape (..., k)) allows and renormalised — where
    an engine would call the evidence impossible. Rows where nothing is left to normalise are NaN.
    """
    check_soft_rule(rule)
    p, q = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(q, dtype=float))
    joint = np.where(p > 0, q, 0.0) if rule == "jeffrey" else p * q
    total = joint.sum(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(total > 0, joint / np.where(total > 0, total, 1.0), np.nan)
