"""Compiled loops of the network's planning (numba, :func:`glu.jit.compiled`): triangulation, the junction
tree, and the schedule of its messages, over bit sets of variables.

:mod:`glu.bn.plan` and :mod:`glu.bn.propagation` call these and describe what they compute; this module holds
only the loops. A set of variables is a row of ``W`` unsigned 64-bit words (variable ``u`` is bit ``u % 64``
of word ``u // 64``), a graph one such row per variable (its neighbours), so that a neighbourhood is ``W``
words and the fill-in a node would add is a count of bits. Every loop is deterministic: ties go to the
smaller index, as in the greedy order :func:`glu.bn.plan.elimination_order` documents.
"""

from __future__ import annotations

import numpy as np

_DEBRUIJN = np.uint64(0x03F79D71B4CA8B09)
_LOWEST = np.zeros(64, dtype=np.int64)
"""The index of a word's lowest set bit, looked up by the top six bits of that bit times ``_DEBRUIJN``."""
_LOWEST[[((1 << i) * int(_DEBRUIJN) % (1 << 64)) >> 58 for i in range(64)]] = np.arange(64)
HEURISTIC_CODES = {"fill-weight": 0, "min-fill": 1, "min-weight": 2, "min-size": 3}
"""The heuristics of :data:`glu.bn.plan.HEURISTICS` as the loops number them."""


def _popcount(x):
    x = x - ((x >> np.uint64(1)) & np.uint64(0x5555555555555555))
    x = (x & np.uint64(0x3333333333333333)) + ((x >> np.uint64(2)) & np.uint64(0x3333333333333333))
    x = (x + (x >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return np.int64((x * np.uint64(0x0101010101010101)) >> np.uint64(56))


def _bit(u):
    return np.uint64(1) << np.uint64(u & 63)


def _count(row):
    """The number of variables in the set ``row``."""
    k = 0
    for w in range(row.shape[0]):
        k += _popcount(row[w])
    return k


def _subset(a, b):
    """Whether the set ``a`` lies inside the set ``b``."""
    for w in range(a.shape[0]):
        if a[w] & ~b[w] != 0:
            return False
    return True


def _put(rows, k, row):
    """``rows[k] = row`` as a loop: numba's assignment of a row compiles its shape-mismatch message, which
    took seconds of the first compilation."""
    for w in range(row.shape[0]):
        rows[k, w] = row[w]


def _members(row, out):
    """The variables of the set ``row`` written to ``out`` in ascending order; returns how many."""
    k = 0
    for w in range(row.shape[0]):
        x = row[w]
        while x != 0:
            low = x & (~x + np.uint64(1))
            out[k] = w * 64 + _LOWEST[(low * _DEBRUIJN) >> np.uint64(58)]
            k += 1
            x ^= low
    return k


def _adjacency(n, ptr, idx):
    """The graph joining the variables of each set ``idx[ptr[s]:ptr[s + 1]]`` (0 … n-1) to one another."""
    W = max(1, (n + 63) // 64)
    adj = np.zeros((n, W), dtype=np.uint64)
    mask = np.zeros(W, dtype=np.uint64)
    for s in range(ptr.shape[0] - 1):
        mask[:] = 0
        for i in range(ptr[s], ptr[s + 1]):
            a = idx[i]
            mask[a >> 6] |= _bit(a)
        for i in range(ptr[s], ptr[s + 1]):
            a = idx[i]
            for w in range(W):
                adj[a, w] |= mask[w]
    for a in range(n):
        adj[a, a >> 6] &= ~_bit(a)
    return adj


def _key(v, adj, logc, heuristic, buf):
    """The greedy key (two numbers, smaller first) of eliminating ``v`` now."""
    d = _members(adj[v], buf)
    weight = logc[v]
    for i in range(d):
        weight += logc[buf[i]]
    weight = round(weight, 9)
    if heuristic == 2:
        return weight, float(d)
    if heuristic == 3:
        return float(d), weight
    fill = 0
    for i in range(d):
        a = buf[i]
        for w in range(adj.shape[1]):
            fill += _popcount(adj[v, w] & ~adj[a, w])
    fill = (fill - d) // 2  # a is a neighbour of v, never of itself
    if heuristic == 1:
        return float(fill), weight
    if fill > 0:
        return 1.0, fill * weight
    return 0.0, weight


def _eliminate_simplicial(adj, alive, order, cliques):
    """The first steps: nodes with at most one neighbour are simplicial whatever comes next, so they go
    first, the smallest first, then those left with at most one neighbour by them. Returns the steps taken."""
    n = adj.shape[0]
    deg = np.zeros(n, dtype=np.int64)
    for v in range(n):
        deg[v] = _count(adj[v])
    buf = np.empty(n, dtype=np.int64)
    stack = np.empty(2 * n + 1, dtype=np.int64)
    top = 0
    for v in range(n - 1, -1, -1):
        if deg[v] <= 1:
            stack[top] = v
            top += 1
    step = np.int64(0)  # not a literal 0, which numba would compile _put for once more
    while top > 0:
        top -= 1
        v = stack[top]
        if not alive[v] or deg[v] > 1:
            continue
        alive[v] = False
        order[step] = v
        _put(cliques, step, adj[v])
        cliques[step, v >> 6] |= _bit(v)
        step += 1
        d = _members(adj[v], buf)
        for i in range(d):
            a = buf[i]
            adj[a, v >> 6] &= ~_bit(v)
            deg[a] -= 1
            if deg[a] <= 1:
                stack[top] = a
                top += 1
        adj[v] = 0
    return step


def _gains(adj, v, a):
    """Whether eliminating ``v`` adds an edge at its neighbour ``a`` (``v`` has another neighbour ``a``
    lacks)."""
    for w in range(adj.shape[1]):
        add = adj[v, w] & ~adj[a, w]
        if w == a >> 6:
            add &= ~_bit(a)
        if add != 0:
            return True
    return False


def _eliminate_greedy(adj, alive, order, cliques, step, logc, heuristic):
    """The steps from ``step`` on: each eliminates the node of the smallest :func:`_key` (ties: the smaller
    index), joins its neighbours to one another and recomputes the keys of the nodes whose neighbourhood
    changed."""
    n, W = adj.shape
    buf = np.empty(n, dtype=np.int64)
    buf2 = np.empty(n, dtype=np.int64)
    k1 = np.full(n, np.inf)
    k2 = np.full(n, np.inf)
    for v in range(n):
        if alive[v]:
            k1[v], k2[v] = _key(v, adj, logc, heuristic, buf)
    touched = np.zeros(n, dtype=np.bool_)
    while step < n:
        v = np.int64(-1)  # not a literal -1: numba would compile the helpers v reaches once more for it
        for u in range(n):
            if alive[u] and (v < 0 or k1[u] < k1[v] or (k1[u] == k1[v] and k2[u] < k2[v])):
                v = u
        alive[v] = False  # as in _eliminate_simplicial: a helper called per step slowed small graphs ~9 %
        order[step] = v
        _put(cliques, step, adj[v])
        cliques[step, v >> 6] |= _bit(v)
        step += 1
        d = _members(adj[v], buf)
        for i in range(d):
            touched[buf[i]] = True
        for i in range(d):
            a = buf[i]
            adj[a, v >> 6] &= ~_bit(v)
            if _gains(adj, v, a):
                if heuristic <= 1:  # a's neighbours see one more edge among theirs: their fill changes
                    d2 = _members(adj[a], buf2)
                    for j in range(d2):
                        touched[buf2[j]] = True
                for w in range(W):
                    adj[a, w] |= adj[v, w]
                adj[a, a >> 6] &= ~_bit(a)
        adj[v] = 0
        for u in range(n):
            if touched[u]:
                touched[u] = False
                if alive[u]:
                    k1[u], k2[u] = _key(u, adj, logc, heuristic, buf)


def eliminate(adj0, logc, heuristic):
    """The greedy elimination order and each step's clique (the node and its neighbours then), shape
    (n,) and (n, W): the nodes of at most one neighbour first (:func:`_eliminate_simplicial`), then the
    greedy steps (:func:`_eliminate_greedy`)."""
    n, W = adj0.shape
    adj = adj0.copy()
    alive = np.ones(n, dtype=np.bool_)
    order = np.empty(n, dtype=np.int64)
    cliques = np.zeros((n, W), dtype=np.uint64)
    step = _eliminate_simplicial(adj, alive, order, cliques)
    _eliminate_greedy(adj, alive, order, cliques, step, logc, heuristic)
    return order, cliques


def _tree(order, cliques):
    """The maximal cliques (bit sets, shape (m, W)) and the edges joining them (shape (m - 1, 2) for a
    tree, sorted), from the elimination cliques: step k joins the step of its clique's first-eliminated
    other node, and a clique inside a child's (running intersection) is merged into it."""
    n, W = cliques.shape
    step = np.empty(n, dtype=np.int64)
    for k in range(n):
        step[order[k]] = k
    parent = np.full(n, -1, dtype=np.int64)
    buf = np.empty(n, dtype=np.int64)
    for k in range(n):
        d = _members(cliques[k], buf)
        for i in range(d):
            u = buf[i]
            if u != order[k] and (parent[k] < 0 or step[u] < parent[k]):
                parent[k] = step[u]
    kptr = np.zeros(n + 1, dtype=np.int64)
    for k in range(n):
        if parent[k] >= 0:
            kptr[parent[k] + 1] += 1
    for k in range(n):
        kptr[k + 1] += kptr[k]
    fill = kptr[:-1].copy()
    kids = np.empty(max(kptr[n], 1), dtype=np.int64)
    for k in range(n):
        p = parent[k]
        if p >= 0:
            kids[fill[p]] = k
            fill[p] += 1
    rep = np.arange(n)
    for k in range(n):
        for j in range(kptr[k], kptr[k + 1]):
            r = rep[kids[j]]
            if _subset(cliques[k], cliques[r]):
                rep[k] = r
                break
    new = np.full(n, -1, dtype=np.int64)
    m = 0
    for k in range(n):
        if rep[k] == k:
            new[k] = m
            m += 1
    kept = np.empty((m, W), dtype=np.uint64)
    for k in range(n):
        if rep[k] == k:
            _put(kept, new[k], cliques[k])
    # each edge once, sorted, as bit sets: joined[a] holds every b > a that a is joined to (np.unique would
    # compile a sort: seconds of the first compilation)
    joined = np.zeros((m, max(1, (m + 63) // 64)), dtype=np.uint64)
    for k in range(n):
        p = parent[k]
        if p >= 0 and rep[k] != rep[p]:
            a, b = new[rep[k]], new[rep[p]]
            joined[min(a, b), max(a, b) >> 6] |= _bit(max(a, b))
    jptr, jidx = members_csr(joined)
    edges = np.empty((jidx.shape[0], 2), dtype=np.int64)
    for a in range(m):
        for e in range(jptr[a], jptr[a + 1]):
            edges[e, 0] = a
            edges[e, 1] = jidx[e]
    return kept, edges


def triangulate(n, ptr, idx, cards, heuristic):
    """Triangulate the graph of the sets ``idx[ptr[s]:ptr[s + 1]]`` over variables 0 … n-1 (cardinalities
    ``cards``) by a greedy heuristic (:data:`HEURISTIC_CODES`).

    Returns (order, maximal cliques as bit sets (m, W), edges (m - 1, 2), entries of each clique's table
    (float: exact up to 2**53, past any table limit) and variables of each, shape (m,))."""
    adj = _adjacency(n, ptr, idx)
    logc = np.empty(n)
    for v in range(n):
        logc[v] = np.log(max(cards[v], 1))
    order, raw = eliminate(adj, logc, heuristic)
    kept, edges = _tree(order, raw)
    m = kept.shape[0]
    sizes = np.ones(m)
    counts = np.zeros(m, dtype=np.int64)
    buf = np.empty(max(n, 1), dtype=np.int64)
    for c in range(m):
        d = _members(kept[c], buf)
        counts[c] = d
        for i in range(d):
            sizes[c] *= cards[buf[i]]
    return order, kept, edges, sizes, counts


def members_csr(sets):
    """The variables of each bit set of ``sets`` (shape (m, W)), ascending, as (ptr, idx)."""
    m = sets.shape[0]
    ptr = np.zeros(m + 1, dtype=np.int64)
    for c in range(m):
        ptr[c + 1] = _count(sets[c])
    for c in range(m):
        ptr[c + 1] += ptr[c]
    idx = np.empty(ptr[m], dtype=np.int64)
    for c in range(m):
        _members(sets[c], idx[ptr[c] :])
    return ptr, idx


def _homes(cliques, sizes, ptr, idx):
    """The smallest clique (of table sizes ``sizes``) holding each set ``idx[ptr[s]:ptr[s + 1]]``: the first
    of the smallest, -1 for an empty set; shape (S,)."""
    m, W = cliques.shape
    S = ptr.shape[0] - 1
    where = np.full(S, -1, dtype=np.int64)
    want = np.zeros(W, dtype=np.uint64)
    for s in range(S):
        if ptr[s + 1] == ptr[s]:
            continue
        want[:] = 0
        for i in range(ptr[s], ptr[s + 1]):
            want[idx[i] >> 6] |= _bit(idx[i])
        best = -1
        for k in range(m):
            if (best < 0 or sizes[k] < sizes[best]) and _subset(want, cliques[k]):
                best = k
        where[s] = best
    return where


def schedule(cliques, sizes, edges, ptr, idx, first_home):
    """Where each set goes and how the tree is rooted and walked.

    ``cliques`` (m, W) bit sets with table sizes ``sizes``; ``edges`` (the tree's); sets
    ``idx[ptr[s]:ptr[s + 1]]`` (variables): returns the home of each (:func:`_homes`), shape (S,); each
    clique's parent (-1: a root), shape (m,); the cliques in breadth-first order from each root, shape
    (m,), and where each tree starts in it; and whether each clique lies on a path from a root to the home
    of a set ``first_home`` or later (the targets). Roots: the targets' homes in ascending order, then the
    lowest clique of each other tree."""
    m = cliques.shape[0]
    where = _homes(cliques, sizes, ptr, idx)
    nptr = np.zeros(m + 1, dtype=np.int64)
    for e in range(edges.shape[0]):
        nptr[edges[e, 0] + 1] += 1
        nptr[edges[e, 1] + 1] += 1
    for c in range(m):
        nptr[c + 1] += nptr[c]
    at = nptr[:-1].copy()
    nidx = np.empty(max(nptr[m], 1), dtype=np.int64)
    for e in range(edges.shape[0]):
        a, b = edges[e, 0], edges[e, 1]
        nidx[at[a]] = b
        at[a] += 1
        nidx[at[b]] = a
        at[b] += 1
    homed = np.zeros(max(1, (m + 63) // 64), dtype=np.uint64)  # the homes as a bit set: ascending, once each
    for s in range(first_home, where.shape[0]):
        if where[s] >= 0:
            homed[where[s] >> 6] |= _bit(where[s])
    homes = np.empty(max(m, 1), dtype=np.int64)
    n_homes = _members(homed, homes)
    parent = np.full(m, -1, dtype=np.int64)
    placed = np.zeros(m, dtype=np.bool_)
    bfs = np.empty(m, dtype=np.int64)
    starts = np.empty(m, dtype=np.int64)
    n_trees = 0
    filled = 0
    for i in range(n_homes + m):
        r = homes[i] if i < n_homes else i - n_homes
        if r < 0 or placed[r]:
            continue
        starts[n_trees] = filled
        n_trees += 1
        placed[r] = True
        bfs[filled] = r
        head = filled
        filled += 1
        while head < filled:
            c = bfs[head]
            head += 1
            for j in range(nptr[c], nptr[c + 1]):
                x = nidx[j]
                if not placed[x]:
                    placed[x] = True
                    parent[x] = c
                    bfs[filled] = x
                    filled += 1
    on_path = np.zeros(m, dtype=np.bool_)
    for i in range(n_homes):
        c = homes[i]
        while c >= 0 and not on_path[c]:
            on_path[c] = True
            c = parent[c]
    return where, parent, bfs, starts[:n_trees], on_path


def plan_pattern(n, ptr, idx, cards, first_home, try_all_above):
    """:func:`triangulate` by the first heuristic — or by each, keeping the smallest total, when the first
    one's tables hold more than ``try_all_above`` entries — then :func:`schedule` of the same sets (those
    from ``first_home`` on are the targets: single variables).

    Returns (heuristic code, order, cliques as bit sets, edges, sizes, counts, the cliques' variables as
    (ptr, idx), then :func:`schedule`'s where, parent, bfs, starts, on_path)."""
    best = np.int64(0)  # not a literal 0: numba would compile triangulate's whole tree once more for it
    order, sets, edges, sizes, counts = triangulate(n, ptr, idx, cards, best)
    if sizes.sum() > try_all_above:
        for h in range(1, 4):
            o, s, e, z, c = triangulate(n, ptr, idx, cards, h)
            if z.sum() < sizes.sum():
                best, order, sets, edges, sizes, counts = h, o, s, e, z, c
    cptr, cidx = members_csr(sets)
    where, parent, bfs, starts, on_path = schedule(sets, sizes, edges, ptr, idx, first_home)
    return best, order, sets, edges, sizes, counts, cptr, cidx, where, parent, bfs, starts, on_path


def support_witness(observed, order, cards, par_ptr, par_idx, cpt_off, flat, max_configs, max_steps):
    """Whether a configuration of positive probability agrees with the hard evidence ``observed`` (a value
    per variable, -1 where unobserved) — found, not proven impossible: False means *not found*.

    Over the evidence's ancestors only (the rest sums to 1): first each variable's allowed values are
    narrowed from the evidence upwards (:func:`_narrow`, families of more than ``max_configs`` parent
    configurations left as they are), then a configuration is searched for downwards (:func:`_search`, at
    most ``max_steps`` steps). A table is ``flat[cpt_off[v]:]`` in the layout (parents…, variable), last
    parent fastest; ``order`` is topological."""
    n = cards.shape[0]
    maxk = 1
    for v in range(n):
        maxk = max(maxk, cards[v])
    need = observed >= 0
    for k in range(n - 1, -1, -1):
        v = order[k]
        if need[v]:
            for i in range(par_ptr[v], par_ptr[v + 1]):
                need[par_idx[i]] = True
    allowed = np.zeros((n, maxk), dtype=np.bool_)
    for v in range(n):
        if need[v]:
            if observed[v] >= 0:
                allowed[v, observed[v]] = True
            else:
                allowed[v, : cards[v]] = True
    _narrow(need, allowed, order, cards, par_ptr, par_idx, cpt_off, flat, max_configs)
    return _search(need, allowed, order, cards, par_ptr, par_idx, cpt_off, flat, max_steps)


def _narrow(need, allowed, order, cards, par_ptr, par_idx, cpt_off, flat, max_configs):
    """Each needed variable's ``allowed`` values narrowed, children before parents: a parent keeps the values
    that some parent configuration of positive probability for an allowed value of the child uses."""
    n, maxk = allowed.shape
    seen = np.zeros((n, maxk), dtype=np.bool_)
    vals = np.zeros(n, dtype=np.int64)
    for k in range(n - 1, -1, -1):
        v = order[k]
        a, b = par_ptr[v], par_ptr[v + 1]
        if not need[v] or a == b:
            continue
        configs = 1
        for i in range(a, b):
            configs *= cards[par_idx[i]]
        if configs > max_configs:
            continue
        for i in range(a, b):
            seen[par_idx[i], :] = False
        for cfg in range(configs):
            rest = cfg
            ok = True
            for i in range(b - 1, a - 1, -1):
                p = par_idx[i]
                vals[i - a] = rest % cards[p]
                rest //= cards[p]
                if not allowed[p, vals[i - a]]:
                    ok = False
            if not ok:
                continue
            base = cpt_off[v] + cfg * cards[v]
            for x in range(cards[v]):
                if allowed[v, x] and flat[base + x] > 0:
                    for i in range(a, b):
                        seen[par_idx[i], vals[i - a]] = True
                    break
        for i in range(a, b):
            p = par_idx[i]
            for x in range(cards[p]):
                allowed[p, x] = allowed[p, x] and seen[p, x]


def _search(need, allowed, order, cards, par_ptr, par_idx, cpt_off, flat, max_steps):
    """Depth first over the needed variables in topological order: each takes its allowed values of
    positive probability given its parents', in order (an observed variable's only allowed value is its
    own); True when every variable has one, False when the search ends or passes ``max_steps``."""
    n = cards.shape[0]
    seq = np.empty(n, dtype=np.int64)
    m = 0
    for k in range(n):
        if need[order[k]]:
            seq[m] = order[k]
            m += 1
    chosen = np.full(n, -1, dtype=np.int64)
    tried = np.zeros(m, dtype=np.int64)  # the next value to try at each place of seq
    pos = 0
    steps = 0
    while pos < m:
        steps += 1
        if steps > max_steps:
            return False
        v = seq[pos]
        cfg = 0
        for i in range(par_ptr[v], par_ptr[v + 1]):
            p = par_idx[i]
            cfg = cfg * cards[p] + chosen[p]
        base = cpt_off[v] + cfg * cards[v]
        found = -1
        for x in range(tried[pos], cards[v]):
            if allowed[v, x] and flat[base + x] > 0:
                found = x
                break
        if found >= 0:
            chosen[v] = found
            tried[pos] = found + 1
            pos += 1
            if pos < m:
                tried[pos] = 0
        else:
            chosen[v] = -1
            pos -= 1
            if pos < 0:
                return False
    return True
