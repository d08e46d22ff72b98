"""Planning exact inference in any discrete network: an elimination order, its junction tree, its size.

The junction tree engine (:mod:`glu.bn.junction`) works on the cliques of a triangulated moral graph. This
module finds them from the structure alone — no table is built — so that the size of the largest table is
known before any memory is spent:

1. the moral graph: each node joined to its parents, and the parents of each node to one another (for a set
   of factors, :func:`plan_from_scopes`: the variables of each factor joined to one another);
2. an elimination order, greedy: at each step the node whose elimination adds the fewest fill-in edges,
   ties broken by the smallest table it creates (the product of the cardinalities of the node and its
   remaining neighbours), then by node order — deterministic;
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
    """

    cards: tuple[int, ...]
    cliques: tuple[tuple[int, ...], ...]
    edges: tuple[tuple[int, int], ...]
    order: tuple[int, ...]
    width: int
    largest: int
    total: int

    def size(self, clique: Sequence[int]) -> int:
        """Entries of the table over ``clique`` (variable indices)."""
        return math.prod(self.cards[v] for v in clique)


def _cost(v: int, adj: list[set[int]], logc: Sequence[float]) -> tuple[int, float, int]:
    nb = list(adj[v])
    fill = 0
    for i, a in enumerate(nb):
        na = adj[a]
        fill += sum(1 for b in nb[i + 1 :] if b not in na)
    return fill, round(logc[v] + sum(logc[u] for u in nb), 9), v


def elimination_order(adj: list[set[int]], cards: Sequence[int]) -> tuple[list[int], list[tuple[int, ...]]]:
    """A greedy min-fill elimination order (ties: smallest table, then index) and the clique of each step.

    ``adj`` is consumed (fill-in edges are added, eliminated nodes removed). Returns (order, cliques): the
    clique of step k is the k-th eliminated node with its neighbours at that time, sorted.
    """
    logc = [math.log(max(c, 1)) for c in cards]
    heap = [_cost(v, adj, logc) for v in range(len(adj))]
    heapq.heapify(heap)
    current = {key[2]: key for key in heap}
    alive = [True] * len(adj)
    order, cliques = [], []
    while heap:
        key = heapq.heappop(heap)
        v = key[2]
        if not alive[v] or current[v] != key:
            continue
        nb = adj[v]
        order.append(v)
        cliques.append(tuple(sorted(nb | {v})))
        alive[v] = False
        touched = set(nb)
        for a in nb:
            adj[a].discard(v)
            new = nb - adj[a] - {a}
            if new:
                adj[a] |= new
        for a in nb:
            touched |= adj[a]
        adj[v] = set()
        for u in touched:
            if alive[u]:
                k = _cost(u, adj, logc)
                if k != current[u]:
                    current[u] = k
                    heapq.heappush(heap, k)
    return order, cliques


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
    adj: list[set[int]] = [set() for _ in keep]
    for scope in scopes:
        sc = [local[v] for v in set(scope)]
        for i, a in enumerate(sc):
            for b in sc[i + 1 :]:
                adj[a].add(b)
                adj[b].add(a)
    order_l, raw_l = elimination_order(adj, [cards[v] for v in keep])
    order = [keep[i] for i in order_l]
    raw = [tuple(keep[i] for i in c) for c in raw_l]
    sizes = [math.prod(cards[v] for v in c) for c in raw]
    largest = max(sizes, default=1)
    width = max((len(c) for c in raw), default=1) - 1
    widest = max((len(c) for c in raw), default=0)
    if widest > MAX_CLIQUE_VARIABLES:
        raise ModelError(
            f"exact inference in this network needs a table over {widest} variables (elimination width "
            f"{width}); NumPy arrays have at most 64 axes, so glu handles up to {MAX_CLIQUE_VARIABLES}"
        )
    if largest > limit:
        worst = raw[sizes.index(largest)]
        raise ModelError(
            f"exact inference in this network needs a table of {largest:,} entries ({len(worst)} "
            f"variables: elimination width {width}); the limit is {limit:,} — raise it with "
            f"--max-table, ${MAX_TABLE_ENV} or max_table= (memory: {_bytes(largest * 8)} for that "
            "table alone)"
        )
    # the elimination tree: clique k joined to the clique of its first-eliminated neighbour
    step = {v: k for k, v in enumerate(order)}
    link: dict[int, set[int]] = {k: set() for k in range(len(raw))}
    for k, (v, c) in enumerate(zip(order, raw, strict=True)):
        later = [step[u] for u in c if u != v]
        if later:
            j = min(later)
            link[k].add(j)
            link[j].add(k)
    cliques = {k: set(c) for k, c in enumerate(raw)}
    merged = True
    while merged:  # a clique inside a neighbouring one joins it (keeps the running intersection)
        merged = False
        for a in sorted(cliques):
            if a not in cliques:
                continue
            sup = next((b for b in sorted(link[a]) if cliques[a] <= cliques[b]), None)
            if sup is None:
                continue
            for c in link[a] - {sup}:
                link[c].discard(a)
                link[c].add(sup)
                link[sup].add(c)
            link[sup].discard(a)
            del cliques[a], link[a]
            merged = True
    keep = sorted(cliques, key=lambda k: (min(cliques[k]), k))
    renum = {k: i for i, k in enumerate(keep)}
    final = tuple(tuple(sorted(cliques[k])) for k in keep)
    edges = tuple(sorted({tuple(sorted((renum[a], renum[b]))) for a in keep for b in link[a]}))
    return JunctionTreePlan(
        cards=cards,
        cliques=final,
        edges=edges,  # type: ignore[arg-type]
        order=tuple(order),
        width=width,
        largest=largest,
        total=sum(math.prod(cards[v] for v in c) for c in final),
    )
