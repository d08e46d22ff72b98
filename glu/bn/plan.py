"""Planning exact inference in any discrete network: an elimination order, its junction tree, its size.

The junction tree engine (:mod:`glu.bn.junction`) works on the cliques of a triangulated moral graph. This
module finds them from the structure alone — no table is built — so that the size of the largest table is
known before any memory is spent:

1. the moral graph: each node joined to its parents, and the parents of each node to one another (for a set
   of factors, :func:`plan_from_scopes`: the variables of each factor joined to one another);
2. an elimination order, greedy: at each step the node whose elimination adds the fewest fill-in edges
   (min-fill), ties broken by the smallest table it creates (the product of the cardinalities of the node
   and its remaining neighbours), then by node order — deterministic. When the tables are large
   (:data:`TRY_ALL_ABOVE`), the orders that take the smallest table first (min-weight) and the fewest
   neighbours first (min-size) are tried too, and the one with the smallest total table size is kept;
3. the cliques: when a node is eliminated, it and its remaining neighbours form one; the elimination tree
   (each clique joined to the clique of its first-eliminated neighbour) is a junction tree, and a clique
   contained in a neighbouring one is merged into it until every clique is maximal.

The *elimination width* is the number of variables of the largest clique minus one; the *largest table*
is the largest product of the cardinalities of a clique's variables. :func:`plan_junction_tree` refuses a
network whose largest table exceeds the limit (:func:`max_table_setting`) in one line that gives both.

>>> plan = plan_junction_tree(
...     ["A", "B", "C", "D"], {"A": (), "B": ("A",), "C": ("A",), "D": ("B", "C")}, [2, 2, 2, 2]
... )
>>> [sorted("ABCD"[v] for v in c) for c in plan.cliques], plan.width, plan.largest
([['A', 'B', 'C'], ['B', 'C', 'D']], 2, 8)
"""

from __future__ import annotations

import heapq
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from glu.errors import ModelError

MAX_TABLE_DEFAULT = 1 << 24
"""The largest clique table the engine builds by default: 16,777,216 entries (128 MiB of float64)."""
MAX_CLIQUE_VARIABLES = 60
"""NumPy arrays have at most 64 axes: a clique of more variables (possible only with one-valued variables,
else its table is far past any limit) is refused like a table past the limit."""
MAX_TABLE_ENV = "GLU_MAX_TABLE"
"""Environment variable that sets the limit for every engine of the process (a whole number ≥ 1)."""


def _bytes(n: float) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:,.0f} {unit}" if unit == "bytes" else f"{n:,.1f} {unit}"
        n /= 1024
    return ""  # pragma: no cover


def max_table_setting(value: int | None = None) -> int:
    """The limit on the largest table: ``value`` if given, else ``$GLU_MAX_TABLE``, else the default.

    Raises :class:`ModelError` (one line) for a limit that is not a whole number ≥ 1.
    """
    where = "max_table"
    if value is None:
        text = os.environ.get(MAX_TABLE_ENV)
        if text is None or not text.strip():
            return MAX_TABLE_DEFAULT
        where = f"${MAX_TABLE_ENV}"
        try:
            value = int(text.replace("_", ""))
        except ValueError:
            raise ModelError(f"{where}={text!r}: expected a whole number of table entries ≥ 1") from None
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ModelError(f"{where}={value!r}: expected a whole number of table entries ≥ 1")
    return value


@dataclass(frozen=True)
class JunctionTreePlan:
    """The cliques of a network and the tree (a forest, for a disconnected network) that joins them.

    Attributes
    ----------
    cards : cardinality of each variable, by variable index (the network's node order)
    cliques : each clique's variable indices, sorted ascending
    edges : the tree's edges, pairs of clique indices
    order : the elimination order (variable indices)
    width : elimination width (variables of the largest clique − 1)
    largest : entries of the largest clique table
    total : entries of all clique tables together
    heuristic : the elimination heuristic kept (:data:`HEURISTICS`)
    """

    cards: tuple[int, ...]
    cliques: tuple[tuple[int, ...], ...]
    edges: tuple[tuple[int, int], ...]
    order: tuple[int, ...]
    width: int
    largest: int
    total: int
    heuristic: str = "min-fill"

    def size(self, clique: Sequence[int]) -> int:
        """Entries of the table over ``clique`` (variable indices)."""
        return math.prod(self.cards[v] for v in clique)


HEURISTICS: tuple[str, ...] = ("fill-weight", "min-fill", "min-weight", "min-size")
"""The greedy elimination heuristics, tried in this order: simplicial nodes first, then the fewest fill-in
edges times the log size of the table made (close to pyAgrum's default); the fewest fill-in edges; the
smallest table; the fewest neighbours."""
TRY_ALL_ABOVE = 1 << 20
"""When the first heuristic's tables hold more entries than this together, the others are tried too and the
smallest total kept (below it, planning four times costs more than the tables)."""


def _bits(mask: int) -> list[int]:
    out = []
    while mask:
        low = mask & -mask
        out.append(low.bit_length() - 1)
        mask ^= low
    return out


def _key(
    v: int, nbs: list[set[int]], masks: list[int], logc: Sequence[float], heuristic: str
) -> tuple[float, float, int]:
    """The greedy key of eliminating ``v`` now (smaller first; ties: the other measure, then the index)."""
    nb = nbs[v]
    weight = round(logc[v] + sum(map(logc.__getitem__, nb)), 9)  # rounded: the same whatever the set order
    if heuristic == "min-weight":
        return weight, len(nb), v
    if heuristic == "min-size":
        return len(nb), weight, v
    m = masks[v]
    fill = (sum((m & ~masks[a]).bit_count() for a in nb) - len(nb)) // 2  # a is in m, never in masks[a]
    if heuristic == "min-fill":
        return fill, weight, v
    return (1.0 if fill else 0.0), (fill * weight if fill else weight), v


def elimination_order(
    adj: Sequence[int], cards: Sequence[int], heuristic: str = HEURISTICS[0]
) -> tuple[list[int], list[int]]:
    """A greedy elimination order by ``heuristic`` (one of :data:`HEURISTICS`) and the clique of each step.

    ``adj`` holds each node's neighbours as a bit mask (bit u = node u; it is not changed). Returns (order,
    cliques): the clique of step k is the k-th eliminated node with its neighbours at that time, as a bit
    mask. Deterministic (ties go to the smaller index).
    """
    masks = list(adj)
    nbs = [set(_bits(m)) for m in masks]
    logc = [math.log(max(c, 1)) for c in cards]
    alive = [True] * len(adj)
    order, cliques = [], []
    # nodes with at most one neighbour are simplicial whatever comes next: eliminated first, no keys needed
    peel = [v for v in range(len(adj)) if len(nbs[v]) <= 1]
    peel.reverse()
    while peel:
        v = peel.pop()
        if not alive[v] or len(nbs[v]) > 1:
            continue
        alive[v] = False
        order.append(v)
        cliques.append(masks[v] | 1 << v)
        for a in nbs[v]:
            nbs[a].discard(v)
            masks[a] &= ~(1 << v)
            if len(nbs[a]) <= 1:
                peel.append(a)
        nbs[v], masks[v] = set(), 0
    current = [_key(v, nbs, masks, logc, heuristic) if alive[v] else None for v in range(len(adj))]
    heap = [k for k in current if k is not None]
    heapq.heapify(heap)
    while heap:
        key = heapq.heappop(heap)
        v = key[2]
        if not alive[v] or current[v] != key:
            continue
        nb, m, bit = nbs[v], masks[v], 1 << v
        order.append(v)
        cliques.append(m | bit)
        alive[v] = False
        touched = set(nb)
        for a in nb:
            na = nbs[a]
            na.discard(v)
            add = nb - na
            add.discard(a)
            if add:
                if heuristic in ("min-fill", "fill-weight"):  # a's neighbours see one more edge among theirs
                    touched |= na
                na |= add
            masks[a] = (masks[a] | m) & ~(1 << a) & ~bit
        nbs[v] = set()
        for u in touched:
            if alive[u]:
                k = _key(u, nbs, masks, logc, heuristic)
                if k != current[u]:
                    current[u] = k
                    heapq.heappush(heap, k)
    return order, cliques


def _tree(order: list[int], raw: list[int]) -> tuple[list[int], list[tuple[int, int]]]:
    """Maximal cliques and the edges joining them, from the elimination cliques (bit masks).

    The elimination tree joins step k to the step of its clique's first-eliminated other node; a clique
    inside another one is inside one of its children there (running intersection), and is merged into it.
    """
    step = {v: k for k, v in enumerate(order)}
    parent = []
    for k, c in enumerate(raw):
        later = [step[u] for u in _bits(c & ~(1 << order[k]))]
        parent.append(min(later) if later else -1)
    kids: list[list[int]] = [[] for _ in raw]
    for k, p in enumerate(parent):
        if p >= 0:
            kids[p].append(k)
    rep = list(range(len(raw)))
    for k, c in enumerate(raw):
        for ch in kids[k]:
            if c & ~raw[rep[ch]] == 0:
                rep[k] = rep[ch]
                break
    keep = sorted({rep[k] for k in range(len(raw))})
    edges = {tuple(sorted((rep[k], rep[p]))) for k, p in enumerate(parent) if p >= 0 and rep[k] != rep[p]}
    return [raw[k] for k in keep], [(keep.index(a), keep.index(b)) for a, b in sorted(edges)]  # type: ignore[misc]


def plan_junction_tree(
    nodes: Sequence[str],
    parents: Mapping[str, Sequence[str]],
    cards: Sequence[int],
    max_table: int | None = None,
) -> JunctionTreePlan:
    """The junction tree of a network, planned from its structure; :class:`ModelError` past the size limit.

    Parameters
    ----------
    nodes : node names, in the network's order (a node's index is its variable index)
    parents : node → its parents' names
    cards : cardinality of each node, shape (n_nodes,)
    max_table : the largest clique table allowed (entries); None: :func:`max_table_setting`

    Raises
    ------
    ModelError
        one line with the largest table the network needs, its elimination width, and the limit
    """
    index = {n: i for i, n in enumerate(nodes)}
    scopes = [(index[n], *(index[p] for p in parents[n])) for n in nodes]
    return plan_from_scopes(cards, scopes, range(len(nodes)), max_table)


def plan_from_scopes(
    cards: Sequence[int],
    scopes: Sequence[Sequence[int]],
    variables: Sequence[int],
    max_table: int | None = None,
) -> JunctionTreePlan:
    """The junction tree of a set of factors over ``variables`` (each scope a set of variable indices).

    The domain graph joins the variables of each scope; :func:`plan_junction_tree` is this with one scope
    per family (a node and its parents: the moral graph). Variables outside ``variables`` must not appear in
    a scope; ``cards`` gives the cardinality of every variable index.
    """
    limit = max_table_setting(max_table)
    cards = tuple(int(c) for c in cards)
    keep = sorted(set(variables))
    local = {v: i for i, v in enumerate(keep)}
    adj = [0] * len(keep)
    for scope in scopes:
        members = [local[v] for v in scope]
        mask = 0
        for a in members:
            mask |= 1 << a
        for a in members:
            adj[a] |= mask
    adj = [m & ~(1 << a) for a, m in enumerate(adj)]
    lcards = [cards[v] for v in keep]
    best = None
    for heuristic in HEURISTICS:
        order_l, raw_l = elimination_order(adj, lcards, heuristic)
        cliques_l, edges = _tree(order_l, raw_l)
        members = [_bits(c) for c in cliques_l]
        sizes = [math.prod(lcards[v] for v in m) for m in members]
        if best is None or sum(sizes) < sum(best[4]):
            best = (heuristic, order_l, members, edges, sizes)
        if heuristic == HEURISTICS[0] and sum(sizes) <= TRY_ALL_ABOVE:
            break
    assert best is not None
    heuristic, order_l, members, edges, sizes = best  # every elimination clique lies in one of these
    final = tuple(tuple(keep[i] for i in m) for m in members)
    largest = max(sizes, default=1)
    widest = max((len(c) for c in final), default=0)
    width = max(widest, 1) - 1
    if widest > MAX_CLIQUE_VARIABLES:
        raise ModelError(
            f"exact inference in this network needs a table over {widest} variables (elimination width "
            f"{width}); NumPy arrays have at most 64 axes, so glu handles up to {MAX_CLIQUE_VARIABLES}"
        )
    if largest > limit:
        worst = final[sizes.index(largest)]
        raise ModelError(
            f"exact inference in this network needs a table of {largest:,} entries ({len(worst)} "
            f"variables: elimination width {width}); the limit is {limit:,} — raise it with "
            f"--max-table, ${MAX_TABLE_ENV} or max_table= (memory: {_bytes(largest * 8)} for that "
            "table alone)"
        )
    return JunctionTreePlan(
        cards=cards,
        cliques=final,
        edges=tuple(edges),
        order=tuple(keep[i] for i in order_l),
        width=width,
        largest=largest,
        total=sum(sizes),
        heuristic=heuristic,
    )
