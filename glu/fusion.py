"""Fusing the gesture HMMs with the Affordance–Words network (GLU 2017 §2.4, TCDS 2020 §III-C).

The HMMs observe the human's hand and give a posterior over the action, ``p_hmm(A | G)``; the network knows
how actions, objects, effects and words go together. The action node ``A`` is the schema's node with
``role: action`` (:func:`glu.schema.action_node`: ``Action`` in GLU's network, ``Tool`` or ``Motion`` in a
lab's own), or the one named with ``action=``. The one home of every fusion rule:

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

:func:`fuse` takes one gesture posterior, shape (K,), or one per frame, shape (T, K), and returns the
posterior of each target with the same leading shape. Observing Action directly makes the gesture evidence
irrelevant; the originals refuse it, and so does :func:`fuse`.

:func:`fuse_tables` and :func:`fuse_action_tables` are the same rules in closed form over the network's
conditional tables, ``p_BN(X_inf | X_obs, A = a)`` and ``p_BN(A | X_obs)``, vectorised over any number of
leading axes (episodes, prefixes): a corpus evaluation queries the network once per distinct ``X_obs`` and
fuses millions of gesture posteriors with array arithmetic. They are tested against :func:`fuse`.

Example
-------
>>> from glu.bn import learn_bn, make_engine
>>> from glu.data import load_experiments
>>> engine = make_engine(learn_bn(load_experiments("synthetic")))
>>> p = fuse(engine, ["ObjVel"], {"Shape": "sphere"}, [0.1, 0.8, 0.1], "virtual")["ObjVel"]
>>> p.shape, round(float(p.sum()), 12)
((3,), 1.0)
>>> fuse(engine, ["ObjVel"], {"Shape": "sphere"}, [[0.1, 0.8, 0.1], [0.8, 0.1, 0.1]],
...      "jeffrey")["ObjVel"].shape
(2, 3)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Literal

import numpy as np

from glu.bn.inference import Engine
from glu.bn.soft import SOFT_RULES, soft_posterior
from glu.errors import EvidenceError
from glu.schema import ACTIONS, action_node

Strategy = Literal["hard", "virtual", "jeffrey", "product"]
STRATEGIES: tuple[str, ...] = ("hard", *SOFT_RULES, "product")
"""Every fusion strategy: hard decision, the two soft rules (the originals' first), the product rule."""
SOFT_STRATEGIES: tuple[str, ...] = (*SOFT_RULES, "product")
"""The strategies that keep the HMMs' doubt (a sweep over p_hmm needs one of these)."""
ACTION = "Action"
"""GLU's action node; other networks name theirs by its role (:func:`glu.schema.action_node`)."""


def check_strategy(strategy: str, allowed: Sequence[str] = STRATEGIES) -> str:
    """``strategy`` if it is among ``allowed``, else :class:`EvidenceError` naming them."""
    if strategy not in allowed:
        raise EvidenceError(f"unknown fusion strategy {strategy!r}; allowed: {', '.join(allowed)}")
    return strategy


def fuse(
    engine: Engine,
    targets: Sequence[str] | str,
    evidence: Mapping[str, str] | None,
    p_hmm: Mapping[str, float] | Sequence[float] | np.ndarray | None,
    strategy: Strategy = "virtual",
    action: str | None = None,
) -> dict[str, np.ndarray]:
    """Posterior marginals of ``targets`` given observed network evidence and the HMM posterior over the
    action.

    Parameters
    ----------
    engine : inference engine of the network
    targets : nodes to infer (the action node among them for action recognition)
    evidence : hard evidence on the other observed nodes (object features, effects, words); must not
        contain the action node
    p_hmm : the gesture posterior over the action in the node's value order: array, shape (K,) — or a
        mapping {action: p} — for one gesture; array, shape (T, K) for T gestures (or T prefixes of one);
        None for no gesture evidence (the network alone)
    strategy : one of :data:`STRATEGIES` (see the module docstring)
    action : the action node; None: the schema's node with ``role: action`` (:func:`glu.schema.action_node`)

    Returns
    -------
    dict target → array, shape (n_values,) for one gesture or (T, n_values) for T
    """
    if isinstance(targets, str):
        targets = [targets]
    evidence = dict(evidence or {})
    check_strategy(strategy)
    if p_hmm is None:
        return engine.query(targets, evidence)
    a = action if action is not None else action_node(engine.bn.schema)
    if a in evidence:
        raise EvidenceError(
            f"{a} is observed directly ({a}={evidence[a]}) and also given by the gesture HMMs; "
            "the gesture evidence would be ignored — drop one of them"
        )
    if strategy == "product" and list(targets) != [a]:
        raise EvidenceError(
            f"the product rule infers the action itself: targets must be [{a!r}], not {list(targets)}"
        )
    if not isinstance(p_hmm, Mapping) and np.ndim(p_hmm) == 2:
        return _fuse_rows(engine, list(targets), evidence, np.asarray(p_hmm, dtype=float), strategy, a)
    q = engine.soft_vector(a, p_hmm)
    if strategy == "hard":
        best = int(np.argmax(q))
        return engine.query(targets, {**evidence, a: best})
    if strategy == "product":  # p_hmm · p_BN(A | X_obs), normalised: virtual evidence with A the target
        return engine.query([a], evidence, soft={a: q}, soft_rule="virtual")
    return engine.query(targets, evidence, soft={a: q}, soft_rule=strategy)


def _fuse_rows(
    engine: Engine,
    targets: list[str],
    evidence: dict[str, str],
    q: np.ndarray,
    strategy: str,
    action: str,
) -> dict[str, np.ndarray]:
    """:func:`fuse` for T posteriors at once, with one batch query."""
    n = len(q)
    columns = {k: [v] * n for k, v in evidence.items()}
    if strategy == "hard":
        return engine.query_batch(targets, {**columns, action: np.argmax(q, axis=1)})
    # the product rule is virtual evidence on the action with the action the only target
    rule = "virtual" if strategy == "product" else strategy
    return engine.query_batch(targets, columns, soft={action: q}, soft_rule=rule)


def hmm_rows(p_tap: Sequence[float] | np.ndarray, actions: Sequence[str] = ACTIONS) -> np.ndarray:
    """HMM posteriors with ``p(tap) = t`` and the rest split equally, shape (len(p_tap), len(actions))."""
    t = np.asarray(p_tap, dtype=float)
    rows = np.empty((t.size, len(actions)))
    i = list(actions).index("tap")
    rows[:] = ((1 - t) / (len(actions) - 1))[:, None]
    rows[:, i] = t
    return rows


def fuse_action_tables(p_a: np.ndarray, p_hmm: np.ndarray, strategy: str) -> np.ndarray:
    """``p(Action | X_obs, G)`` by each rule, in closed form, vectorised over leading axes.

    Parameters
    ----------
    p_a : array, shape (..., K) — the network's ``p_BN(A | X_obs)``
    p_hmm : array, shape (..., K) — the gesture posterior (broadcast against ``p_a``)
    strategy : one of :data:`STRATEGIES`: ``hard`` puts all mass on ``argmax p_hmm`` (first on ties, as
        :func:`fuse`); ``virtual`` and ``product`` give ``p_a · p_hmm`` normalised; ``jeffrey`` gives
        ``p_hmm`` itself (its rule fixes the marginal of Action) — restricted to the actions the evidence
        allows (``p_a > 0``) and renormalised, where :func:`fuse` would refuse the evidence as impossible

    Returns
    -------
    array, shape (..., K); rows where nothing is left to normalise are NaN (virtual, product, jeffrey)
    """
    check_strategy(strategy)
    p_a, q = np.broadcast_arrays(np.asarray(p_a, dtype=float), np.asarray(p_hmm, dtype=float))
    if strategy == "hard":
        out = np.zeros(q.shape)
        np.put_along_axis(out, np.argmax(q, axis=-1)[..., None], 1.0, axis=-1)
        return out
    return soft_posterior(p_a, q, "jeffrey" if strategy == "jeffrey" else "virtual")


def fuse_tables(p_x_given_a: np.ndarray, p_a: np.ndarray, p_hmm: np.ndarray, strategy: str) -> np.ndarray:
    """``p(X_inf | X_obs, G)`` for a target other than Action by each rule, in closed form, vectorised.

    Parameters
    ----------
    p_x_given_a : array, shape (..., K, V) — ``p_BN(X_inf = v | X_obs, A = a)``; the V entries may be the
        values of one node or independent marginals (e.g. ``P(word present)`` for every word)
    p_a : array, shape (..., K) — ``p_BN(A | X_obs)``
    p_hmm : array, shape (..., K) — the gesture posterior
    strategy : ``hard`` (``p(x | A = argmax p_hmm)``), ``virtual``
        (``Σ_a p(x | a) p_a q_a / Σ_a p_a q_a``) or ``jeffrey`` (``Σ_a p(x | a) q_a``); the product rule
        infers the action itself (:func:`fuse_action_tables`)

    Returns
    -------
    array, shape (..., V); NaN where virtual evidence meets ``Σ_a p_a q_a = 0``
    """
    check_strategy(strategy)
    if strategy == "product":
        raise EvidenceError("the product rule infers the action itself: use fuse_action_tables")
    w = fuse_action_tables(p_a, p_hmm, strategy)  # the weight of each action: hard, p(A | X_obs, G), q
    return np.einsum("...k,...kv->...v", w, np.asarray(p_x_given_a, dtype=float))
