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

import itertools
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from glu.bn import kernels
from glu.bn.kernels import HEURISTIC_CODES
from glu.errors import ModelError
from glu.jit import compiled

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


HEURISTICS: tuple[str, ...] = ("fill-weight", "min-fill", "min-weight", "min-size")
"""The greedy elimination heuristics, tried in this order: simplicial nodes first, then the fewest fill-in
edges times the log size of the table made (close to pyAgrum's default); the fewest fill-in edges; the
smallest table; the fewest neighbours."""
TRY_ALL_ABOVE = 1 << 20
"""When the first heuristic's tables hold more entries than this together, the others are tried too and the
smallest total kept (below it, planning four times costs more than the tables)."""


def _words(masks: Sequence[int], n: int) -> np.ndarray:
    """Python-int bit masks as rows of 64-bit words, shape (len(masks), W)."""
    W = max(1, (n + 63) // 64)
    return np.array([[(m >> (64 * w)) & (2**64 - 1) for w in range(W)] for m in masks], dtype=np.uint64)


def _mask(words: np.ndarray) -> int:
    return sum(int(x) << (64 * w) for w, x in enumerate(words))


def elimination_order(
    adj: Sequence[int], cards: Sequence[int], heuristic: str = HEURISTICS[0]
) -> tuple[list[int], list[int]]:
    """A greedy elimination order by ``heuristic`` (one of :data:`HEURISTICS`) and the clique of each step.

    ``adj`` holds each node's neighbours as a bit mask (bit u = node u; it is not changed). Returns (order,
    cliques): the clique of step k is the k-th eliminated node with its neighbours at that time, as a bit
    mask. Deterministic: nodes with at most one neighbour go first (they are simplicial whatever comes
    next), the smallest first; then, at each step, the node of the smallest key (ties: the smaller index).
    """
    logc = np.log(np.maximum(np.asarray(cards, dtype=float), 1.0))
    order, cliques = compiled(kernels.eliminate)(_words(adj, len(adj)), logc, HEURISTIC_CODES[heuristic])
    return order.tolist(), [_mask(c) for c in cliques]


class Triangulation(NamedTuple):
    """The junction tree of a graph over local variables 0 … n-1, and where sets of them go in it
    (:func:`triangulate`).

    Attributes
    ----------
    heuristic : the heuristic kept (:data:`HEURISTICS`)
    order : its elimination order, shape (n,)
    sets : the maximal cliques as bit sets (:mod:`glu.bn.kernels`), shape (m, W)
    edges : the tree's edges, sorted, shape (m - 1, 2) for a connected graph (a forest has fewer)
    sizes : entries of each clique's table (float), shape (m,)
    counts : variables of each clique, shape (m,)
    ptr, idx : the variables of clique c are ``idx[ptr[c]:ptr[c + 1]]``, ascending
    where : the smallest clique holding each set (the first of the smallest; -1 for an empty set)
    parent : each clique's parent when the trees are rooted (-1: a root), shape (m,)
    bfs, starts : the cliques breadth first from each root (parents before children), and where each tree
        starts in ``bfs``; the roots are the homes of the sets from ``first_home`` on (ascending), then the
        first clique of each other tree
    on_path : whether each clique lies on the path from a root to one of those homes, shape (m,)
    """

    heuristic: str
    order: np.ndarray
    sets: np.ndarray
    edges: np.ndarray
    sizes: np.ndarray
    counts: np.ndarray
    ptr: np.ndarray
    idx: np.ndarray
    where: np.ndarray
    parent: np.ndarray
    bfs: np.ndarray
    starts: np.ndarray
    on_path: np.ndarray


def triangulate(
    n: int, ptr: np.ndarray, idx: np.ndarray, cards: np.ndarray, first_home: int | None = None
) -> Triangulation:
    """The junction tree of the graph joining the variables of each set ``idx[ptr[s]:ptr[s + 1]]`` (local
    variables 0 … n-1 of cardinalities ``cards``, int64 arrays): by the first of :data:`HEURISTICS`, or —
    past :data:`TRY_ALL_ABOVE` entries — by the one of the smallest total; the trees rooted at the homes
    of the sets from ``first_home`` on (None: no set).

    ``ptr``, shape (n_sets + 1,), ascending from 0; ``idx``, shape (ptr[-1],); ``cards``, shape (n,).
    """
    home = len(ptr) - 1 if first_home is None else first_home
    res = compiled(kernels.plan_pattern)(n, ptr, idx, cards, home, TRY_ALL_ABOVE)
    return Triangulation(HEURISTICS[res[0]], *res[1:])


def check_size(tri: Triangulation, limit: int, variables: Sequence[int], cards: Sequence[int]) -> None:
    """:class:`ModelError` (one line: the largest table, the elimination width, the limit) when a clique
    of ``tri`` has more variables than NumPy's axes allow or a table past ``limit`` entries
    (``variables``: the global index of each local variable, for the exact size in the message)."""
    widest = max(tri.counts.tolist(), default=0)
    width = max(widest, 1) - 1
    if widest > MAX_CLIQUE_VARIABLES:
        raise ModelError(
            f"exact inference in this network needs a table over {widest} variables (elimination width "
            f"{width}); NumPy arrays have at most 64 axes, so glu handles up to {MAX_CLIQUE_VARIABLES}"
        )
    if max(tri.sizes.tolist(), default=1) > limit:
        worst = int(np.argmax(tri.sizes))
        members = tri.idx[tri.ptr[worst] : tri.ptr[worst + 1]].tolist()
        largest = math.prod(cards[variables[i]] for i in members)
        if largest > limit:
            raise ModelError(
                f"exact inference in this network needs a table of {largest:,} entries ({len(members)} "
                f"variables: elimination width {width}); the limit is {limit:,} — raise it with "
                f"--max-table, ${MAX_TABLE_ENV} or max_table= (memory: {_bytes(largest * 8)} for that "
                "table alone)"
            )


def triangulate_sets(
    variables: Iterable[int],
    sets: Sequence[Sequence[int]],
    cards: Sequence[int],
    max_table: int | None = None,
    first_home: int | None = None,
) -> tuple[Triangulation, tuple[tuple[int, ...], ...]]:
    """:func:`triangulate` of the graph joining the variables of each of ``sets`` (indices among
    ``variables``; ``cards``: the cardinality of every index), checked by :func:`check_size` against
    ``max_table`` (:func:`max_table_setting`); and each clique's variables, as those indices, sorted."""
    limit = max_table_setting(max_table)
    keep = sorted(set(variables))
    local = {v: i for i, v in enumerate(keep)}
    ptr = np.cumsum([0, *map(len, sets)], dtype=np.int64)
    idx = np.array([local[u] for s in sets for u in s], dtype=np.int64)
    tri = triangulate(len(keep), ptr, idx, np.array([cards[v] for v in keep], dtype=np.int64), first_home)
    check_size(tri, limit, keep, cards)
    members = np.array(keep, dtype=np.int64)[tri.idx].tolist()
    return tri, tuple(tuple(members[a:b]) for a, b in itertools.pairwise(tri.ptr.tolist()))


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
    cards = tuple(int(c) for c in cards)
    tri, cliques = triangulate_sets(variables, scopes, cards, max_table)
    keep = sorted(set(variables))
    sizes = [math.prod(cards[v] for v in c) for c in cliques]
    return JunctionTreePlan(
        cards=cards,
        cliques=cliques,
        edges=tuple(map(tuple, tri.edges.tolist())),
        order=tuple(keep[i] for i in tri.order.tolist()),
        width=max(int(tri.counts.max(initial=0)), 1) - 1,
        largest=max(sizes, default=1),
        total=sum(sizes),
        heuristic=tri.heuristic,
    )
