"""Fusing the gesture HMMs with the Affordance–Words network (GLU 2017 §2.4, TCDS 2020 §III-C).

The HMMs observe the human's hand and give a posterior over the action, ``p_hmm(A | G)``; the BN knows
how actions, objects, effects and words go together. Four ways to combine them, one interface:

``hard``
    the top HMM action becomes hard evidence: ``p_BN(X_inf | X_obs, A = argmax p_hmm)``.
``virtual``
    soft decision as the originals implement it, ``p_hmm`` as virtual (likelihood) evidence on Action:
    ``p(X_inf | X_obs, G) ∝ Σ_A p_BN(X_inf, A | X_obs) p_hmm(A | G)``. When Action itself is a target this
    is TCDS's ``p_comb(A | X_obs, G) ∝ p_BN(A | X_obs) p_hmm(A | G)`` — the product rule — so the TCDS
    case split (Action inferred vs latent) is the same computation.
``jeffrey``
    soft evidence by Jeffrey's rule, which fixes the marginal of Action to ``p_hmm``:
    ``p(X_inf | X_obs, G) = Σ_a p_BN(X_inf | X_obs, A=a) p_hmm(a | G)``.
``product``
    the product rule for the action itself, ``p(A) ∝ p_hmm(A | G) p_BN(A | X_obs)`` (targets must be
    Action only; numerically the ``virtual`` rule restricted to Action).

Observing Action directly makes the gesture evidence irrelevant; the originals refuse it, and so does
:func:`fuse`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Literal

import numpy as np

from glu.bn.inference import InferenceEngine
from glu.errors import EvidenceError

Strategy = Literal["hard", "virtual", "jeffrey", "product"]
STRATEGIES: tuple[str, ...] = ("hard", "virtual", "jeffrey", "product")
ACTION = "Action"


def fuse(
    engine: InferenceEngine,
    targets: Sequence[str] | str,
    evidence: Mapping[str, str] | None,
    p_hmm: Mapping[str, float] | Sequence[float] | np.ndarray | None,
    strategy: Strategy = "virtual",
) -> dict[str, np.ndarray]:
    """Posterior marginals of ``targets`` given observed BN evidence and the HMM posterior over Action.

    Parameters
    ----------
    engine : inference engine of the Affordance–Words network
    targets : nodes to infer (``"Action"`` among them for action recognition)
    evidence : hard evidence on the other observed nodes (object features, effects, words); must not
        contain Action
    p_hmm : the gesture posterior over Action (a vector in the node's value order, or {action: p}); None
        means no gesture evidence (the BN alone)
    strategy : ``"hard"``, ``"virtual"``, ``"jeffrey"`` or ``"product"`` (see the module docstring)

    Returns
    -------
    dict target → array, shape (n_values,)
    """
    if isinstance(targets, str):
        targets = [targets]
    evidence = dict(evidence or {})
    if strategy not in STRATEGIES:
        raise EvidenceError(f"unknown fusion strategy {strategy!r}; allowed: {', '.join(STRATEGIES)}")
    if p_hmm is None:
        return engine.query(targets, evidence)
    if ACTION in evidence:
        raise EvidenceError(
            f"Action is observed directly (Action={evidence[ACTION]}) and also given by the gesture HMMs; "
            "the gesture evidence would be ignored — drop one of them"
        )
    q = engine.soft_vector(ACTION, p_hmm)
    if strategy == "hard":
        best = int(np.argmax(q))
        return engine.query(targets, {**evidence, ACTION: best})
    if strategy == "product":
        if list(targets) != [ACTION]:
            raise EvidenceError(
                f"the product rule infers the action itself: targets must be ['Action'], not {list(targets)}"
            )
        p_bn = engine.query([ACTION], evidence)[ACTION]
        p = p_bn * q
        if p.sum() <= 0:
            raise engine._impossible(evidence, {ACTION: q})
        return {ACTION: p / p.sum()}
    return engine.query(targets, evidence, soft={ACTION: q}, soft_rule=strategy)


def hmm_rows(
    p_tap: Sequence[float] | np.ndarray, actions: Sequence[str] = ("grasp", "tap", "touch")
) -> np.ndarray:
    """HMM posteriors with ``p(tap) = t`` and the rest split equally, shape (len(p_tap), 3)."""
    t = np.asarray(p_tap, dtype=float)
    rows = np.empty((t.size, len(actions)))
    i = list(actions).index("tap")
    rows[:] = ((1 - t) / (len(actions) - 1))[:, None]
    rows[:, i] = t
    return rows
