"""Hugin propagation on a junction tree, vectorised over rows of evidence: the arithmetic of both plans.

A :class:`QueryPlan` says, for one evidence pattern, which tables to start from, which messages to send
and where to read each target's marginal; :func:`propagate` runs it on tables whose *last* axis is the
rows (size 1 for a table that is the same in every row: NumPy broadcasting keeps the work of the parts of
the tree that no evidence reaches at one row). With the rows last, every product and sum runs its inner
loop over a contiguous run of rows, whatever the clique's shape. The junction tree engine
(:mod:`glu.bn.junction`) builds two kinds of plan: on the network's one junction tree, with the messages of
the network without evidence computed in advance; and on the junction tree of the network conditioned on an
evidence pattern (:mod:`glu.bn.conditioned`), whose smaller tables pay off over a batch of rows.

Messages are not rescaled, unless a root's mass falls below :data:`TINY` (or to 0, which could be an
underflow): then the plan runs again with every new message normalised to sum 1 per row, so that evidence
of very small probability is answered, and only evidence of probability exactly 0 is called impossible.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

TINY = 1e-250
"""A root mass below this may have lost digits to underflow: the plan runs again with normalised messages."""

Edge = tuple[int, int, tuple[int, ...], tuple[int, ...]]


@dataclass(frozen=True, eq=False)
class QueryPlan:
    """How one evidence pattern is propagated; built by the junction tree engine, run by :func:`propagate`.

    Attributes
    ----------
    base : clique → its starting table, shape ``(*cardinalities of its variables, 1)``
    collect : (child, parent, summed axes, shape in the parent) — new messages, children first (a shape
        ends with -1, the rows)
    distribute : (parent, child, summed axes, shape in the child, fresh) — messages towards the targets,
        parents first; ``fresh`` False: the message ``messages[parent, child]`` computed in advance
    roots : the root of each tree with evidence; its mass is the probability of the evidence (up to scale)
    targets : (variable, clique, summed axes) — marginals read from the clique's table
    prior : variable → marginal without evidence (targets in trees that no evidence reaches), shape (k,)
    messages : (from, to) → message computed in advance, for ``fresh`` False and for the collect messages
        a plan does not send (their product is in ``base``)
    entries : (variable, clique, shape) — where each evidence node's likelihood enters (the static plan)
    size : entries of all tables in ``base`` (the memory a row costs)
    """

    base: dict[int, np.ndarray]
    collect: tuple[Edge, ...]
    distribute: tuple[tuple[int, int, tuple[int, ...], tuple[int, ...], bool], ...]
    roots: tuple[int, ...]
    targets: tuple[tuple[int, int, tuple[int, ...]], ...]
    prior: dict[int, np.ndarray] = field(default_factory=dict)
    messages: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)
    entries: tuple[tuple[int, int, tuple[int, ...]], ...] = ()

    @property
    def size(self) -> int:
        """Entries of all tables in ``base``."""
        return sum(t.size for t in self.base.values())


def propagate(
    plan: QueryPlan,
    entries: Sequence[tuple[int, np.ndarray]],
    rows: int,
    normalise: bool = False,
    mass: bool = False,
) -> tuple[dict[int, np.ndarray], np.ndarray, np.ndarray | None]:
    """Run ``plan`` with ``entries``: (clique, array broadcastable over its table, rows last) multiplied in.

    Returns (marginals, possible, log mass): variable → normalised marginal, shape (rows, k) (NaN in
    impossible rows); whether each row's evidence has probability > 0, shape (rows,); with ``mass``, the
    log of the probability of the evidence in the trees it reaches (up to the plan's constant factors),
    shape (rows,), else None.
    """
    reduce = np.add.reduce
    table = dict(plan.base)
    for c, arr in entries:
        table[c] = table[c] * arr
    up: dict[int, np.ndarray] = {}
    scales = []
    for c, p, axes, shape in plan.collect:
        m = reduce(table[c], axis=axes)
        if normalise:
            s = reduce(m.reshape(-1, m.shape[-1]), axis=0)
            s = np.where(s > 0, s, 1.0)
            scales.append(s)
            m = m / s
        up[c] = m
        table[p] = table[p] * m.reshape(shape)
    z = [reduce(table[r].reshape(-1, table[r].shape[-1]), axis=0) for r in plan.roots]
    if not normalise and any(bool((x < TINY).any()) for x in z):
        return propagate(plan, entries, rows, normalise=True, mass=mass)
    possible = np.ones(rows, dtype=bool)
    for x in z:
        possible &= x > 0
    log_mass = None
    if mass:
        with np.errstate(divide="ignore"):
            log_mass = sum((np.log(x) for x in z + scales), np.zeros(rows))
    for p, c, axes, shape, fresh in plan.distribute:
        if fresh:
            m = reduce(table[p], axis=axes)
            old = up.get(c)
            if old is None:
                old = plan.messages[c, p]
            m = np.divide(m, old, out=np.zeros(m.shape), where=old > 0)
        else:
            m = plan.messages[p, c]
        table[c] = table[c] * m.reshape(shape)
    out = {}
    ok = bool(possible.all())
    for v, c, axes in plan.targets:
        m = reduce(table[c], axis=axes).T  # (rows, k)
        if ok:
            m = m / reduce(m, axis=1).reshape(-1, 1)
        else:
            with np.errstate(invalid="ignore", divide="ignore"):
                m = m / reduce(m, axis=1).reshape(-1, 1)
            m[~possible] = np.nan
        out[v] = m if len(m) == rows else np.broadcast_to(m, (rows, m.shape[1]))
    for v, marginal in plan.prior.items():
        out[v] = np.broadcast_to(marginal, (rows, len(marginal)))
    return out, possible, log_mass


def components(n: int, neighbours: Sequence[Sequence[int]]) -> list[int]:
    """The tree (connected component) of each clique, named by its smallest clique."""
    comp = [-1] * n
    for start in range(n):
        if comp[start] >= 0:
            continue
        stack = [start]
        comp[start] = start
        while stack:
            c = stack.pop()
            for nb in neighbours[c]:
                if comp[nb] < 0:
                    comp[nb] = start
                    stack.append(nb)
    return comp


def orient(root: int, neighbours: Sequence[Sequence[int]]) -> tuple[list[int], dict[int, int | None]]:
    """The cliques of ``root``'s tree, parents before children, and each clique's parent (root: None)."""
    order = [root]
    parent: dict[int, int | None] = {root: None}
    k = 0
    while k < len(order):
        c = order[k]
        k += 1
        for nb in neighbours[c]:
            if nb not in parent:
                parent[nb] = c
                order.append(nb)
    return order, parent


def sum_axes(clique: Sequence[int], keep: Sequence[int]) -> tuple[int, ...]:
    """Axes of a clique's table (rows last) to sum out to keep the variables ``keep``."""
    k = set(keep)
    return tuple(i for i, v in enumerate(clique) if v not in k)


def shape_in(variables: Sequence[int], clique: Sequence[int], cards: Sequence[int]) -> tuple[int, ...]:
    """The shape, rows last (-1), of a table over ``variables`` (sorted) broadcast over ``clique``."""
    s = set(variables)
    return (*(cards[v] if v in s else 1 for v in clique), -1)


def paths_to(root_order: Sequence[int], parent: dict[int, int | None], homes: Sequence[int]) -> set[int]:
    """The cliques on the paths from the root to each of ``homes`` (the root included when any)."""
    needed: set[int] = set()
    for h in homes:
        c: int | None = h
        while c is not None and c not in needed:
            needed.add(c)
            c = parent[c]
    return needed
