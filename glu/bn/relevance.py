"""Relevance before any arithmetic: which nodes and which evidence a query needs (d-separation, barren nodes).

Every engine answers a query from the part of the network the query needs, found from the structure alone:

* :func:`reachable` — the nodes d-connected to some evidence given the evidence (an active trail, Koller &
  Friedman's algorithm 3.1, from every evidence node at once). A target outside it has its prior marginal
  whatever the evidence says, and is answered from the engine's cached priors.
* :func:`requisite` — Shachter's Bayes-ball from the targets: the nodes whose tables the answer needs (every
  other node is barren or d-separated from the targets, and left out), and the evidence it needs (evidence
  the ball does not reach cannot change the answer, and is not used — as in pyAgrum's relevance reasoning).

Soft (virtual) evidence on a node acts as an observed child of it, and so does a table whose rows do not
all sum to 1 (the original's all-zero word rows, which exclude configurations in every query): such nodes
are never barren. Nodes are variable indices; ``parents`` and ``children`` index lists.

>>> parents = [(), (0,), (0,), (1, 2)]          # A → B, A → C, (B, C) → D
>>> children = [(1, 2), (3,), (3,), ()]
>>> sorted(reachable(parents, children, hard={1}, virtual=set()))   # B observed: A, C and D stay connected
[0, 2, 3]
>>> r = requisite(parents, children, hard={3}, virtual=set(), targets=[0])
>>> sorted(r.tables), sorted(r.hard)                                # D's table links A to the evidence
([0, 1, 2, 3], [3])
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from glu.bn import kernels
from glu.bn.network import NetworkArrays, code_of
from glu.jit import compiled

WITNESS_CONFIGS = 1 << 16
"""A family with more parent configurations than this is not narrowed by :func:`surely_possible`."""
WITNESS_QUICK_STEPS = 1 << 8
"""The steps of :func:`surely_possible`'s first search, without narrowing the values."""
WITNESS_STEPS = 1 << 12
"""The steps :func:`surely_possible`'s search may take before it gives up (and the query keeps the tables
that check the evidence's probability)."""


def reachable(
    parents: Sequence[Sequence[int]],
    children: Sequence[Sequence[int]],
    hard: Collection[int],
    virtual: Collection[int],
) -> set[int]:
    """The unobserved nodes d-connected to some evidence given the hard evidence.

    Parameters
    ----------
    parents, children : each node's parents and children (variable indices)
    hard : hard-evidence nodes (observed)
    virtual : nodes with an observed virtual child (soft evidence, or a table with rows not summing to 1)
    """
    # nodes with an observed descendant (themselves observed, or given a virtual child): active colliders
    active: set[int] = set()
    stack = [*hard, *virtual]
    while stack:
        v = stack.pop()
        if v not in active:
            active.add(v)
            stack.extend(parents[v])
    out: set[int] = set()
    up: set[int] = set()  # visited, arriving from a child
    down: set[int] = set()  # visited, arriving from a parent
    rising: list[int] = [v for v in virtual if v not in hard]  # to visit, arriving from a child
    falling: list[int] = []  # to visit, arriving from a parent
    for e in hard:
        rising.extend(parents[e])
        falling.extend(children[e])
    while rising or falling:
        while rising:
            v = rising.pop()
            if v in up or v in hard:  # an observed node blocks a trail arriving from below
                continue
            up.add(v)
            out.add(v)
            rising.extend(parents[v])
            falling.extend(children[v])
        while falling:
            v = falling.pop()
            if v in down:
                continue
            down.add(v)
            if v not in hard:
                out.add(v)
                falling.extend(children[v])
            if v in active:  # a collider with an observed descendant passes the trail back up
                rising.extend(parents[v])
    return out


@dataclass(frozen=True)
class Requisite:
    """What a query needs (:func:`requisite`).

    Attributes
    ----------
    tables : nodes whose tables enter the computation (Bayes-ball's *top* marks)
    hard : hard-evidence nodes the answer depends on (the others are d-separated from the targets)
    virtual : virtual-evidence nodes the answer depends on
    """

    tables: frozenset[int]
    hard: frozenset[int]
    virtual: frozenset[int]


def requisite(
    parents: Sequence[Sequence[int]],
    children: Sequence[Sequence[int]],
    hard: Collection[int],
    virtual: Collection[int],
    targets: Iterable[int],
) -> Requisite:
    """Shachter's Bayes-ball from ``targets`` (unobserved nodes) given ``hard`` and ``virtual`` evidence."""
    top: set[int] = set()
    bottom: set[int] = set()
    seen_hard: set[int] = set()
    seen_virtual: set[int] = set()
    todo = [(t, True) for t in targets]
    while todo:
        v, from_child = todo.pop()
        if v in hard:
            seen_hard.add(v)
            if not from_child and v not in top:  # an observed node passes a ball from a parent back up
                top.add(v)
                todo.extend((p, True) for p in parents[v])
            continue
        if from_child and v not in top:
            top.add(v)
            todo.extend((p, True) for p in parents[v])
        if v not in bottom:
            bottom.add(v)
            todo.extend((c, False) for c in children[v])
            if v in virtual:  # its observed virtual child sends the ball back up through v
                seen_virtual.add(v)
                todo.append((v, True))
    return Requisite(frozenset(top), frozenset(seen_hard), frozenset(seen_virtual))


def surely_possible(net: NetworkArrays, hard: Mapping[int, int | np.ndarray]) -> bool:
    """Whether one row of hard evidence is shown to have probability > 0 by a configuration of positive
    probability that agrees with it (:func:`glu.bn.kernels.support_witness`); False: not shown (it may still
    be possible). Only for tables whose rows sum to 1 (no inexact node): then such a configuration of the
    evidence's ancestors is a positive term of P(evidence).

    When it holds, a query may leave out the evidence that cannot reach its targets without losing the
    check that the evidence is possible — the relevance that tables with zeros otherwise forbid. ``hard``:
    variable → value code, a Python int or a batch row's array of shape (1,)."""
    arrays = net.support_arrays()
    observed = arrays[-1].copy()
    for v, c in hard.items():
        observed[v] = code_of(c)
    search = compiled(kernels.support_witness)
    # a quick search first (most evidence: microseconds), then one after narrowing the values
    return bool(
        search(observed, *arrays[:-1], 0, WITNESS_QUICK_STEPS)
        or search(observed, *arrays[:-1], WITNESS_CONFIGS, WITNESS_STEPS)
    )
