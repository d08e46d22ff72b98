"""A network as the engines see it: variable indices, cardinalities, families, tables.

:class:`NetworkArrays` is made once per network (and kept with it: a new engine of the same network starts
from it) from a :class:`~glu.bn.model.BayesNet` in time linear in the network (no table is copied: a table
that is already float64 is used as it is). A :class:`BayesNet` has rows that sum to 1 (within
:data:`glu.bn.model.ROW_TOL`) except the all-zero rows that only word nodes may have, so only the word nodes'
tables are looked at to find the *inexact* nodes (tables with such rows).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from glu.bn.model import BayesNet


@dataclass(eq=False)
class NetworkArrays:
    """A network as variable indices (the network's node order).

    Attributes
    ----------
    names : node names
    index : node name → variable index
    cards : cardinality of each variable
    parents, children : each variable's parents (CPT axis order) and children, as indices
    cpts : each node's table, shape ``(*parent cardinalities, cardinality)``, float64
    inexact : the nodes whose tables have all-zero rows (parent configurations a word never saw): each acts
        as an observed child of the node (relevance), and such a node is never barren
    """

    names: tuple[str, ...]
    index: dict[str, int]
    cards: tuple[int, ...]
    parents: tuple[tuple[int, ...], ...]
    children: tuple[tuple[int, ...], ...]
    cpts: tuple[np.ndarray, ...]
    inexact: frozenset[int]

    @classmethod
    def of(cls, bn: BayesNet) -> NetworkArrays:
        """The arrays of ``bn``: made on the first call and kept with ``bn`` (a frozen network: its tables
        are checked once and never changed), so a new engine of the same network starts from them."""
        made = _ARRAYS.get(bn)
        if made is None:
            made = _ARRAYS[bn] = cls._make(bn)
        return made

    @classmethod
    def _make(cls, bn: BayesNet) -> NetworkArrays:
        names = bn.nodes
        index = {n: i for i, n in enumerate(names)}
        bparents = bn.parents
        parents = tuple(tuple(index[p] for p in bparents[n]) for n in names)
        kids: list[list[int]] = [[] for _ in names]
        for v, ps in enumerate(parents):
            for p in ps:
                kids[p].append(v)
        cpts = tuple(np.asarray(bn.cpts[n], dtype=np.float64) for n in names)
        return cls(
            names=names,
            index=index,
            cards=tuple(c.shape[-1] for c in cpts),
            parents=parents,
            children=tuple(tuple(k) for k in kids),
            cpts=cpts,
            inexact=frozenset(
                index[w] for w in bn.schema.word_nodes if not cpts[index[w]].sum(axis=-1).all()
            ),
        )

    def family(self, v: int) -> tuple[int, ...]:
        """The axes of ``v``'s table as variables: its parents, then itself."""
        return (*self.parents[v], v)

    @cached_property
    def _sorted_families(self) -> list[tuple[int, ...]]:
        return [tuple(sorted((*ps, u))) for u, ps in enumerate(self.parents)]

    def sorted_family(self, v: int) -> tuple[int, ...]:
        """``v`` and its parents in ascending order (the axes of :meth:`sorted_cpt`)."""
        return self._sorted_families[v]

    def sorted_cpt(self, v: int) -> np.ndarray:
        """``v``'s table with its axes in the order of :meth:`sorted_family` (a view, made on first use),
        shape ``tuple(cards[u] for u in sorted_family(v))``."""
        tables = self.__dict__.setdefault("_sorted_cpts", {})
        t = tables.get(v)
        if t is None:
            fam = self.family(v)
            t = tables[v] = np.transpose(self.cpts[v], [fam.index(u) for u in self.sorted_family(v)])
        return t

    @cached_property
    def topological_order(self) -> tuple[int, ...]:
        """The variables, each after all its parents (Kahn's order, ties by index), made on first use."""
        pending = [len(ps) for ps in self.parents]
        order = [v for v, k in enumerate(pending) if k == 0]
        for v in order:
            for c in self.children[v]:
                pending[c] -= 1
                if pending[c] == 0:
                    order.append(c)
        return tuple(order)

    @cached_property
    def zero_above(self) -> tuple[bool, ...]:
        """Whether each node's table, or a table of one of its ancestors, holds a zero (evidence on the node
        may then have probability 0), made on first use."""
        zero = [not bool(t.all()) for t in self.cpts]
        for v in self.topological_order:  # parents first
            zero[v] = zero[v] or any(zero[p] for p in self.parents[v])
        return tuple(zero)

    def support_arrays(self) -> tuple[np.ndarray, ...]:
        """The network as :func:`glu.bn.kernels.support_witness` reads it, made on first use: (a topological
        order, cards, parents as (ptr, idx), each table's offset in ``flat``, every table flattened, and -1
        for each variable: the observed values of no evidence, to copy).

        For V variables: int64 arrays of shapes (V,), (V,), (V + 1,), (n_arcs,), (V,), the float64 ``flat``
        of shape (Σ table sizes,), and (V,).
        """
        return self._support

    @cached_property
    def _support(self) -> tuple[np.ndarray, ...]:
        sizes = [t.size for t in self.cpts]
        return (
            np.array(self.topological_order, dtype=np.int64),
            np.array(self.cards, dtype=np.int64),
            np.cumsum([0, *map(len, self.parents)], dtype=np.int64),
            np.array([p for ps in self.parents for p in ps], dtype=np.int64),
            np.cumsum([0, *sizes[:-1]], dtype=np.int64),
            np.concatenate([t.ravel() for t in self.cpts]),
            np.full(len(self.cards), -1, dtype=np.int64),  # no variable observed: a template
        )

    def ancestors(self, nodes: set[int] | frozenset[int]) -> set[int]:
        """``nodes`` and all their ancestors."""
        out: set[int] = set()
        stack = list(nodes)
        while stack:
            v = stack.pop()
            if v not in out:
                out.add(v)
                stack.extend(self.parents[v])
        return out


_ARRAYS: weakref.WeakKeyDictionary[BayesNet, NetworkArrays] = weakref.WeakKeyDictionary()
"""Each live network's arrays (:meth:`NetworkArrays.of`)."""


def code_of(c: int | np.ndarray) -> int:
    """A single row's value code: a query's hard evidence is a Python int, a batch row's a (1,) array."""
    return c if type(c) is int else int(c[0])
