"""Junction-tree propagation for one evidence pattern, over rows of evidence, keeping what did not change.

A :class:`PatternPlan` is made once per *evidence pattern* — which nodes carry hard evidence, which carry soft
evidence, which nodes are asked for — from the tables the query needs (:mod:`glu.bn.relevance`: barren and
d-separated nodes are left out) with the hard-evidence nodes *conditioned out*: each table that involves
one is sliced at the observed values, so those nodes leave the domain graph and the fill-in they caused.
What is left is triangulated (:mod:`glu.bn.plan`) and its junction tree oriented towards the targets.

:func:`propagate` runs a plan on tables whose *last* axis is the rows (a single query is a batch of one
row; a table the same in every row keeps a row axis of 1, and NumPy broadcasting does the rest): the
evidence enters as row slices of the tables and likelihood vectors, messages flow from the leaves of the
tree to the root (a clique of a target), and — when several cliques hold targets — out again along the paths
to them (Hugin: the message back divides out the one that came up). Each target's marginal is summed out of
its smallest clique.

**Incremental evidence.** For single queries the plan keeps the last query's clique tables and messages. A
message depends only on the evidence below it, so the next query recomputes just the tables whose evidence
changed and the messages on the way from them to the root: changing one evidence value of five costs a
fraction of the first query, and asking the same again costs nothing.

Messages are not rescaled unless a root's mass falls below :data:`TINY` (or to 0, which could be an
underflow): then the plan runs again with every message normalised to sum 1 per row, so that evidence of
very small probability is answered and only evidence of probability exactly 0 is called impossible.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from glu.bn.network import NetworkArrays, code_of
from glu.bn.plan import triangulate_sets

_ONE_ENTRY = np.ones((1,))
_ONE_ENTRY.flags.writeable = False  # the table of a clique no table without evidence falls in: broadcast
_ALL = {1: np.ones(1, dtype=bool)}
_ALL[1].flags.writeable = False  # a single row's "possible", shared: never written to
TINY = 1e-250
"""A root mass below this may have lost digits to underflow: the plan runs again with normalised messages."""

Factor = tuple[np.ndarray, tuple[int, ...], tuple[int, ...], tuple[int, ...]]
"""A table sliced per row: (table with the observed axes flattened last, observed slots, strides, shape in
its clique with the rows last)."""


@dataclass(eq=False)
class PatternPlan:
    """How one evidence pattern is propagated (see the module docstring); made by :func:`make_plan`.

    Attributes
    ----------
    cliques : each clique's variables, sorted
    observed, soft : the conditioned (hard-evidence) variables and the likelihood variables — the evidence
        *slots*, in this order (slot i is bit i of the masks below)
    base : clique → the product of its tables that no evidence touches, shape ``(*cardinalities, 1)``
    factors : clique → its tables sliced per row (:data:`Factor`)
    constants : the sliced tables left with no free variable (a number per row: part of P(evidence))
    const_slots : bit mask of the slots the constants read
    likelihoods : clique → (slot, shape in the clique with the rows last)
    local : clique → bit mask of the slots that enter it
    below : clique → bit mask of the slots in its subtree (towards its root)
    kids : clique → (child, shape of the child's message in the clique)
    collect : (clique, parent, summed axes), children first — one message each
    roots : the root of each tree
    distribute : (parent, clique, summed axes, shape in the clique) — parents first, on the paths to targets
    size : entries of all clique tables (the memory one row costs)
    last : clique → the last step of ``distribute`` that reads its table (after it, the table is let go)
    homes : clique → the targets read from it, (variable, summed axes)
    """

    cliques: tuple[tuple[int, ...], ...]
    observed: tuple[int, ...]
    soft: tuple[int, ...]
    base: list[np.ndarray]
    factors: list[list[Factor]]
    constants: list[Factor]
    likelihoods: list[list[tuple[int, tuple[int, ...]]]]
    local: list[int]
    below: list[int]
    kids: list[list[tuple[int, tuple[int, ...]]]]
    collect: tuple[tuple[int, int, tuple[int, ...]], ...]
    roots: tuple[int, ...]
    distribute: tuple[tuple[int, int, tuple[int, ...], tuple[int, ...]], ...]
    size: int
    last: dict[int, int] = field(default_factory=dict)
    homes: dict[int, list[tuple[int, tuple[int, ...]]]] = field(default_factory=dict)
    const_slots: int = 0
    state: _State | None = field(default=None, repr=False)


@dataclass(eq=False)
class _State:
    """What the last single query left: its evidence signature, its messages and masses, and its answer."""

    signature: tuple
    ups: list[np.ndarray | None]
    z: list[np.ndarray | None]
    mass: bool = False
    const: np.ndarray | None = None
    answer: tuple[dict[int, np.ndarray], np.ndarray, np.ndarray | None] | None = None


def make_plan(
    net: NetworkArrays,
    tables: Sequence[int],
    observed: Sequence[int],
    soft: Sequence[int],
    targets: Sequence[int],
    max_table: int | None = None,
) -> PatternPlan:
    """The plan for hard evidence on ``observed``, likelihoods on ``soft`` and the marginals of ``targets``.

    ``tables`` are the nodes whose tables the answer needs (:func:`glu.bn.relevance.requisite`). Raises
    :class:`~glu.errors.ModelError` (one line) when a table would pass ``max_table``. The graph, its
    triangulation, the home of each table, likelihood and target (its smallest clique) and the order of the
    messages come from one compiled call (:func:`glu.bn.plan.triangulate_sets`: the sets whose homes it finds
    are the tables' free scopes, the ``soft`` variables and the ``targets``, in this order); here the tables
    are built (:func:`_clique_tables`) and the messages laid out (:func:`_schedule`).
    """
    cards = net.cards
    obs = tuple(sorted(observed))
    slot = {v: i for i, v in enumerate(obs)}
    soft = tuple(sorted(soft))
    tables = sorted(tables)
    scopes = [net.sorted_family(v) for v in tables]
    if slot:
        scopes = [
            sc if slot.keys().isdisjoint(sc) else tuple(u for u in sc if u not in slot) for sc in scopes
        ]
    free = {u for sc in scopes for u in sc}.union(soft, targets)
    sets = [*scopes, *((v,) for v in soft), *((v,) for v in targets)]
    tri, cliques = triangulate_sets(free, sets, cards, max_table, len(scopes) + len(soft))
    at = [{v: i for i, v in enumerate(c)} for c in cliques]  # each clique's axis of each of its variables
    where = tri.where.tolist()
    base, factors, constants, local_slots = _clique_tables(net, tables, scopes, where, slot, at)
    likelihoods: list[list[tuple[int, tuple[int, ...]]]] = [[] for _ in cliques]
    for i, v in enumerate(soft):
        c = where[len(scopes) + i]
        likelihoods[c].append((len(obs) + i, _shape_in([v], at[c], cards)))
        local_slots[c] |= 1 << (len(obs) + i)
    homes: dict[int, list[tuple[int, tuple[int, ...]]]] = {}
    for v, h in sorted(zip(targets, where[len(scopes) + len(soft) :], strict=True)):
        homes.setdefault(h, []).append((v, tuple(i for i, u in enumerate(cliques[h]) if u != v)))
    return _schedule(
        tri, cliques, at, cards, obs, soft, base, factors, constants, likelihoods, local_slots, homes
    )


def _shape_in(variables: Iterable[int], axis: dict[int, int], cards: Sequence[int]) -> tuple[int, ...]:
    """The shape, rows last (-1), of a table over ``variables`` broadcast over the table of a clique whose
    variables sit on the axes ``axis``."""
    shape = [1] * (len(axis) + 1)
    shape[-1] = -1
    for u in variables:
        shape[axis[u]] = cards[u]
    return tuple(shape)


def _clique_tables(
    net: NetworkArrays,
    tables: Sequence[int],
    scopes: Sequence[tuple[int, ...]],
    where: Sequence[int],
    slot: dict[int, int],
    at: Sequence[dict[int, int]],
) -> tuple[list[np.ndarray], list[list[Factor]], list[Factor], list[int]]:
    """Each clique's tables: (base, factors, constants, local slots) of :class:`PatternPlan` — the table of
    node ``tables[i]`` (free variables ``scopes[i]``) goes to clique ``where[i]``.

    A clique's base is the product of its tables of no observed variable: a view of the table when there is
    one (no copy), broadcast to the clique's shape when it misses some of its variables."""
    cards = net.cards
    base: list[np.ndarray | None] = [None] * len(at)
    factors: list[list[Factor]] = [[] for _ in at]
    constants: list[Factor] = []
    local_slots = [0] * len(at)
    for v, rest, c in zip(tables, scopes, where, strict=False):
        if len(rest) == len(net.parents[v]) + 1:  # no observed variable in its family
            x = net.sorted_cpt(v).reshape(_shape_in(rest, at[c], cards))
            b = base[c]
            base[c] = x if b is None else b * x
            continue
        fam = net.family(v)
        seen = [u for u in fam if u in slot]
        axes = tuple(fam.index(u) for u in (*rest, *seen))
        table = net.cpts[v] if axes == tuple(range(len(fam))) else net.cpts[v].transpose(axes)
        flat = np.ascontiguousarray(table.reshape(*(cards[u] for u in rest), -1))
        # the last observed variable varies fastest
        strides = tuple(math.prod(cards[u] for u in seen[i + 1 :]) for i in range(len(seen)))
        entry = (flat, tuple(slot[u] for u in seen), strides, ())
        if c < 0:
            constants.append(entry)
        else:
            factors[c].append((flat, entry[1], strides, _shape_in(rest, at[c], cards)))
            for u in seen:
                local_slots[c] |= 1 << slot[u]
    for c, b in enumerate(base):
        full = (*(cards[u] for u in at[c]), 1)
        if b is None or b.shape != full:
            base[c] = np.broadcast_to(_ONE_ENTRY if b is None else b, full)
    return base, factors, constants, local_slots  # type: ignore[return-value]


def _schedule(tri, cliques, at, cards, obs, soft, base, factors, constants, likelihoods, local, homes):  # type: ignore[no-untyped-def]
    """The messages of a plan: each tree rooted at a target's clique, collected, distributed to targets."""
    n = len(cliques)
    parent, bfs, on_path = tri.parent.tolist(), tri.bfs.tolist(), tri.on_path.tolist()
    starts = [*tri.starts.tolist(), n]
    trees = [bfs[a:b] for a, b in itertools.pairwise(starts)]

    def message(c: int, p: int) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """(the axes of ``c`` summed for the message to ``p``, the message's shape in ``p``, rows last)."""
        into = at[p]
        shape = [1] * (len(cliques[p]) + 1)
        shape[-1] = -1
        summed = []
        for i, u in enumerate(cliques[c]):
            j = into.get(u)
            if j is None:
                summed.append(i)
            else:
                shape[j] = cards[u]
        return tuple(summed), tuple(shape)

    below = list(local)
    kids: list[list[tuple[int, tuple[int, ...]]]] = [[] for _ in range(n)]
    collect = []
    distribute = []
    for order in trees:
        for c in reversed(order[1:]):
            p = parent[c]
            summed, shape = message(c, p)
            below[p] |= below[c]
            kids[p].append((c, shape))
            collect.append((c, p, summed))
        for c in order[1:]:
            if on_path[c]:
                p = parent[c]
                distribute.append((p, c, *message(p, c)))
    return PatternPlan(
        cliques=cliques,
        observed=obs,
        soft=soft,
        base=base,
        factors=factors,
        constants=constants,
        likelihoods=likelihoods,
        local=local,
        below=below,
        kids=kids,
        collect=tuple(collect),
        roots=tuple(order[0] for order in trees),
        distribute=tuple(distribute),
        last={p: k for k, (p, _, _, _) in enumerate(distribute)},
        homes=homes,
        size=int(tri.sizes.sum()),
        const_slots=sum({1 << s for entry in constants for s in entry[1]}),
    )


def _pick(entry: Factor, codes: Sequence[np.ndarray], ints: Sequence[int] | None) -> np.ndarray:
    """A sliced table's rows: ``table[..., Σ code · stride]``, shape (*rest, rows). ``ints``: a single row's
    codes as Python ints, when there is one row (then the slice is a view: no copy, no index arithmetic)."""
    table, slots, strides, _ = entry
    if ints is not None:
        i = 0
        for s, st in zip(slots, strides, strict=True):
            i += ints[s] * st
        return table[..., i : i + 1]
    flat = codes[slots[0]] * strides[0] if strides[0] != 1 else codes[slots[0]]
    for s, st in zip(slots[1:], strides[1:], strict=True):
        flat = flat + codes[s] * st
    return table[..., flat]


def propagate(
    plan: PatternPlan,
    codes: Sequence[np.ndarray],
    likelihoods: Sequence[np.ndarray],
    rows: int,
    signature: tuple | None = None,
    mass: bool = False,
) -> tuple[dict[int, np.ndarray], np.ndarray, np.ndarray | None]:
    """Run ``plan`` for ``rows`` evidence sets.

    Parameters
    ----------
    codes : per observed slot, value indices, shape (rows,), all ≥ 0 (one row: a Python int will do)
    likelihoods : per soft slot, shape (rows, k)
    signature : for a single query, the evidence as a hashable tuple per slot: the plan then reuses the
        tables and messages of its last query that no changed slot reaches (None: compute everything)
    mass : also return the log of each row's probability of the evidence

    Returns
    -------
    (target → marginal, shape (rows, k) — NaN in impossible rows; possible, shape (rows,); log mass or None)
    """
    state = plan.state
    changed = -1
    if signature is not None and state is not None and state.mass == mass:
        changed = 0
        for i, (a, b) in enumerate(zip(signature, state.signature, strict=True)):
            if a is not b and a != b:
                changed |= 1 << i
        if changed == 0 and state.answer is not None:
            return state.answer
    n = len(plan.cliques)
    if changed == -1 or state is None:
        state = _State(signature or (), [None] * n, [None] * len(plan.roots), mass)
    out = _run(plan, state, codes, likelihoods, rows, changed, False, mass)
    normalised = out is None
    if normalised:  # a root mass below TINY: again, every message normalised
        state = _State(signature or (), [None] * n, [None] * len(plan.roots), mass)
        out = _run(plan, state, codes, likelihoods, rows, -1, True, mass)
        assert out is not None
    if signature is not None and not normalised:  # kept only unscaled, so that the masses stay exact
        state.signature = signature
        state.answer = out
        plan.state = state
    else:
        plan.state = None
    return out


def _evidence(plan, state, codes, ints, rows, changed, lowest, scales):  # type: ignore[no-untyped-def]
    """(possible, shape (rows,); log P(evidence) when ``scales`` is given, else None) from the roots' masses
    ``state.z`` (the smallest ``lowest``), the constants, and the scales of a normalised pass."""
    if plan.constants and (state.const is None or plan.const_slots & changed):
        const = _pick(plan.constants[0], codes, ints).reshape(-1)
        for entry in plan.constants[1:]:
            const = const * _pick(entry, codes, ints).reshape(-1)
        state.const = const
    const, z = state.const, state.z
    if lowest > 0 and (const is None or (const[0] > 0 if len(const) == 1 else bool((const > 0).all()))):
        possible = _ALL[rows] if rows in _ALL else np.ones(rows, dtype=bool)
    else:
        possible = np.ones(rows, dtype=bool)
        for x in z:
            possible &= x > 0
        if const is not None:
            possible &= const > 0
    log_mass = None
    if scales is not None:
        with np.errstate(divide="ignore"):
            log_mass = sum((np.log(x) for x in z + scales), np.log(const if const is not None else 1.0))
    return possible, log_mass


def _run(plan, state, codes, likelihoods, rows, changed, normalise, mass):  # type: ignore[no-untyped-def]
    """One pass of :func:`propagate`; None when it must be run again normalised.

    Only messages are kept (between single queries, those below unchanged evidence): a clique's table is
    made when it sends or is read, and let go after — the memory a pass holds is the clique tables of the
    network (the parts no evidence touches) and one table at a time per path, not a copy of every clique.
    """
    reduce = np.add.reduce
    ups = state.ups
    ints = [code_of(c) for c in codes] if rows == 1 else None
    scales = []

    def table(c: int) -> np.ndarray:
        """Clique ``c``'s table times the messages from below it, shape ``(*cardinalities, rows)`` (its
        variables' cardinalities): a rows axis of 1 when nothing in it differs by row."""
        t = plan.base[c]
        for entry in plan.factors[c]:
            t = t * _pick(entry, codes, ints).reshape(entry[3])
        for s, shape in plan.likelihoods[c]:
            t = t * likelihoods[s - len(codes)].T.reshape(shape)
        for ch, shape in plan.kids[c]:
            t = t * ups[ch].reshape(shape)
        return t

    for c, _, axes in plan.collect:
        if ups[c] is None or plan.below[c] & changed:
            m = reduce(table(c), axis=axes)
            if normalise:
                s = reduce(m.reshape(-1, m.shape[-1]), axis=0)
                s = np.where(s > 0, s, 1.0)
                scales.append(s)
                m = m / s
            ups[c] = m
    z, full = state.z, {}
    for k, r in enumerate(plan.roots):
        if z[k] is None or plan.below[r] & changed or r in plan.last or r in plan.homes:
            t = full[r] = table(r)
            z[k] = reduce(t.reshape(-1, t.shape[-1]), axis=0)
    lowest = min((float(x[0]) if len(x) == 1 else float(x.min()) for x in z), default=1.0)
    if not normalise and lowest < TINY:
        return None
    possible, log_mass = _evidence(plan, state, codes, ints, rows, changed, lowest, scales if mass else None)
    ok = bool(possible.all())
    out: dict[int, np.ndarray] = {}

    def read(c: int) -> None:
        for v, axes in plan.homes.get(c, ()):
            m = reduce(full[c], axis=axes).T  # (rows, k), divided by its own sum: no entry rounds past 1
            if ok:
                m = m / reduce(m, axis=1, keepdims=True)
            else:
                with np.errstate(invalid="ignore", divide="ignore"):
                    m = m / reduce(m, axis=1, keepdims=True)
                if len(m) != rows:
                    m = np.repeat(m, rows, axis=0)
                m[~possible] = np.nan
            out[v] = m if len(m) == rows else np.broadcast_to(m, (rows, m.shape[1]))

    for r in plan.roots:
        if r in full:
            read(r)
    for k, (p, c, axes, shape) in enumerate(plan.distribute):
        m = reduce(full[p], axis=axes)
        old = ups[c]
        m = np.divide(m, old, out=np.zeros(np.broadcast_shapes(m.shape, old.shape)), where=old > 0)
        if plan.last[p] == k:
            del full[p]
        full[c] = table(c) * m.reshape(shape)
        read(c)
        if c not in plan.last:
            del full[c]
    return out, possible, log_mass
