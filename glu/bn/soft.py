"""Soft evidence on a network node: the two rules and what a valid soft distribution is.

A soft observation of a node X is a distribution ``q`` over its values (for Action: the gesture HMMs'
posterior ``p_HMM(A | G)``). It enters the network by one of two rules (docs/method.md §2.2):

``virtual``
    virtual (likelihood) evidence, ``p(Y | e) ∝ Σ_x p(Y, x | e) q(x)`` — the originals' soft fusion;
``jeffrey``
    Jeffrey's rule, which makes the posterior marginal of X equal to ``q``:
    ``p(Y | e) = Σ_x p(Y | e, x) q(x)``.
"""

from __future__ import annotations

from typing import Literal

from glu.errors import EvidenceError

SoftRule = Literal["virtual", "jeffrey"]
SOFT_RULES: tuple[str, ...] = ("virtual", "jeffrey")
"""The soft-evidence rules, the originals' first."""
SUM_TOL = 1e-6
"""A soft distribution must sum to 1 within this."""


def check_soft_rule(rule: str) -> str:
    """``rule`` if it is one of :data:`SOFT_RULES`, else :class:`EvidenceError` naming the allowed ones."""
    if rule not in SOFT_RULES:
        raise EvidenceError(f"unknown soft rule {rule!r}; allowed: {', '.join(SOFT_RULES)}")
    return rule
