"""The junction tree engine: exact inference in any discrete network, vectorised over evidence sets.

:class:`JunctionTreeEngine` answers the queries of :class:`~glu.bn.inference.InferenceEngine` on the
junction tree that :mod:`glu.bn.plan` finds (its size is checked against the limit before any table is
built). It uses the Hugin architecture with messages normalised to sum to 1, on tables with a leading
axis of rows — one row for a single query, ``n`` for ``n`` evidence sets in one batch:

1. once per network: each clique's table, the product of the CPTs assigned to it; the messages of the
   network without evidence along every edge, in both directions; the marginal of every node;
2. once per *evidence pattern* (which nodes carry evidence, which nodes are asked for; :class:`QueryPlan`,
   cached): a root (a clique of a target), which cliques must send a new message (those below which there
   is evidence) and which must receive one (those on the way to a target's clique), and for every other
   edge the message without evidence, multiplied into the tables in advance;
3. per query: evidence enters as likelihood vectors (one-hot for hard evidence, ``q`` for virtual
   evidence) in one clique each, the new messages flow to the root and out to the targets' cliques, and
   each target's marginal is summed out of its smallest clique.

Jeffrey's rule is virtual evidence with the likelihood that makes the node's marginal ``q``:
``λ(x) = q(x) / p(x | other evidence)``; on several nodes, iterative proportional fitting of the
likelihoods, one node at a time (the fixed point of :class:`~glu.bn.core.CoreEngine`'s IPFP on the joint).
Evidence of probability zero raises :class:`~glu.errors.ImpossibleEvidenceError` (a batch can give that
row NaN instead). A virtual likelihood is first scaled so that its largest entry is 1; if that leaves
nothing (a likelihood of 1e-320 on the only value the hard evidence allows), the row is answered again
with the likelihood scaled on the values the hard evidence allows, as the core engine does.

>>> from glu.bn import InferenceEngine
>>> from glu.bn.exchange import from_bif
>>> bn = from_bif('''
... variable Rain { type discrete [ 2 ] { no, yes }; }
... variable Sprinkler { type discrete [ 2 ] { off, on }; }
... variable Wet { type discrete [ 2 ] { dry, wet }; }
... probability ( Rain ) { table 0.8, 0.2; }
... probability ( Sprinkler | Rain ) { (no) 0.6, 0.4; (yes) 0.99, 0.01; }
... probability ( Wet | Rain, Sprinkler ) { (no, off) 1.0, 0.0; (no, on) 0.1, 0.9;
...                                         (yes, off) 0.2, 0.8; (yes, on) 0.01, 0.99; }
... ''')
>>> eng = InferenceEngine(bn, method="junction")
>>> eng.posterior("Rain", {"Wet": "wet"}).round(4).to_dict()  # 0.2·(0.99·0.8 + 0.01·0.99) / 0.44838
{'no': 0.6423, 'yes': 0.3577}
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from glu.bn.batch import _batch_length
from glu.bn.inference import IPFP_MAX_ITER, IPFP_TOL, InferenceEngine, Method, SoftEvidence
from glu.bn.model import BayesNet
from glu.bn.plan import JunctionTreePlan, plan_junction_tree
from glu.bn.soft import SUM_TOL, SoftRule, check_soft_rule
from glu.errors import EvidenceError, ImpossibleEvidenceError

PLAN_CACHE = 64
"""Query plans kept per engine (one per evidence pattern and set of targets)."""
TINY = 1e-250
"""A root mass below this may have lost digits to underflow: the plan runs again with normalised messages."""
BATCH_ENTRIES = 1 << 22
"""A batch is answered in chunks of rows whose tables hold at most this many entries together (32 MiB)."""


@dataclass(frozen=True, eq=False)
class QueryPlan:
    """How one evidence pattern is propagated (see the module docstring); built by :meth:`JunctionTreeEngine.plan`.

    Attributes
    ----------
    base : clique → its table times the no-evidence messages from the children that send none, (1, *cards)
    entries : (variable, clique, shape) — where each evidence node's likelihood enters, and its shape there
    collect : (child, parent, summed axes, shape in the parent) — new messages, children first
    distribute : (parent, child, summed axes, shape in the child, fresh) — messages towards the targets,
        parents first; ``fresh`` False: the no-evidence message (no evidence outside the child's subtree)
    roots : the root of each tree with evidence
    targets : (variable, clique, summed axes) for targets in trees with evidence
    prior_targets : variables answered with their marginal without evidence (trees without evidence)
    """

    base: dict[int, np.ndarray]
    entries: tuple[tuple[int, int, tuple[int, ...]], ...]
    collect: tuple[tuple[int, int, tuple[int, ...], tuple[int, ...]], ...]
    distribute: tuple[tuple[int, int, tuple[int, ...], tuple[int, ...], bool], ...]
    roots: tuple[int, ...]
    targets: tuple[tuple[int, int, tuple[int, ...]], ...]
    prior_targets: tuple[int, ...]


class JunctionTreeEngine(InferenceEngine):
    """Exact inference in any discrete :class:`BayesNet` by junction tree propagation (see the module docstring).

    Parameters
    ----------
    bn : the network
    method : ignored (``"junction"``); accepted so that ``InferenceEngine(bn, method=…)`` can build it
    max_table : the largest clique table allowed (entries); None: ``$GLU_MAX_TABLE`` or the default of
        :mod:`glu.bn.plan`

    Attributes
    ----------
    tree : the :class:`~glu.bn.plan.JunctionTreePlan` (cliques, edges, elimination width, table sizes)
    """

    def __init__(self, bn: BayesNet, method: Method = "junction", max_table: int | None = None) -> None:
        self._setup(bn, "junction")
        nodes = bn.nodes
        self.index = {n: i for i, n in enumerate(nodes)}
        self.cards = tuple(bn.schema.cardinality(n) for n in nodes)
        self.tree: JunctionTreePlan = plan_junction_tree(nodes, bn.parents, self.cards, max_table)
        cliques = self.tree.cliques
        self.neighbours: list[list[int]] = [[] for _ in cliques]
        for a, b in self.tree.edges:
            self.neighbours[a].append(b)
            self.neighbours[b].append(a)
        self.component = _components(len(cliques), self.neighbours)
        self.home = [
            min((c for c, cl in enumerate(cliques) if v in cl), key=self._clique_size)
            for v in range(len(nodes))
        ]
        """The smallest clique of each variable: where its evidence enters and its marginal is read."""
        self.potential = [np.ones((1, *(self.cards[v] for v in cl))) for cl in cliques]
        for n in nodes:
            family = [self.index[p] for p in bn.parents[n]] + [self.index[n]]
            fam = set(family)
            c = min((k for k, cl in enumerate(cliques) if fam <= set(cl)), key=self._clique_size)
            perm = np.argsort(family)
            table = np.transpose(bn.cpts[n], perm)
            shape = [self.cards[v] if v in fam else 1 for v in cliques[c]]
            self.potential[c] = self.potential[c] * table.reshape(1, *shape)
        self._prior_messages()
        self._plans: OrderedDict[tuple, QueryPlan] = OrderedDict()

    def _clique_size(self, c: int) -> tuple[int, int]:
        return self.tree.size(self.tree.cliques[c]), c

    # ------------------------------------------------------------------ structure helpers
    def _sum_axes(self, a: int, b: int) -> tuple[int, ...]:
        """Axes of clique ``a``'s table (rows first) summed out for the message to clique ``b``."""
        sep = set(self.tree.cliques[b])
        return tuple(1 + i for i, v in enumerate(self.tree.cliques[a]) if v not in sep)

    def _shape_in(self, a: int, b: int) -> tuple[int, ...]:
        """The shape (without rows) of a message from ``a`` broadcast over clique ``b``'s table."""
        sep = set(self.tree.cliques[a])
        return tuple(self.cards[v] if v in sep else 1 for v in self.tree.cliques[b])

    def _prior_messages(self) -> None:
        """Messages of the network without evidence along every directed edge, and every node's marginal."""
        cliques = self.tree.cliques
        self.prior_msg: dict[tuple[int, int], np.ndarray] = {}
        for root in sorted(set(self.component)):
            order, parent = _orient(root, self.neighbours)
            for c in reversed(order[1:]):  # collect, children first
                t = self.potential[c]
                for ch in self.neighbours[c]:
                    if ch != parent[c]:
                        t = t * self.prior_msg[ch, c].reshape(1, *self._shape_in(ch, c))
                p = parent[c]
                self.prior_msg[c, p] = t.sum(axis=self._sum_axes(c, p))
            for c in order:  # distribute, parents first: the product of every other incoming message
                for ch in self.neighbours[c]:
                    if ch == parent[c]:
                        continue
                    t = self.potential[c]
                    for nb in self.neighbours[c]:
                        if nb != ch:
                            t = t * self.prior_msg[nb, c].reshape(1, *self._shape_in(nb, c))
                    self.prior_msg[c, ch] = t.sum(axis=self._sum_axes(c, ch))
        self.prior_mass: dict[int, float] = {}
        self.prior_marginal: list[np.ndarray] = []
        full = []
        for c in range(len(cliques)):
            t = self.potential[c]
            for nb in self.neighbours[c]:
                t = t * self.prior_msg[nb, c].reshape(1, *self._shape_in(nb, c))
            full.append(t)
            self.prior_mass.setdefault(self.component[c], float(t.sum()))
        for v, h in enumerate(self.home):
            axes = tuple(1 + i for i, u in enumerate(cliques[h]) if u != v)
            m = full[h].sum(axis=axes)[0]
            total = m.sum()
            self.prior_marginal.append(m / total if total > 0 else np.full(m.shape, np.nan))

    def plan(self, evidence: frozenset[int], targets: frozenset[int]) -> QueryPlan:
        """The :class:`QueryPlan` for evidence on ``evidence`` and marginals of ``targets`` (variable indices), cached."""
        key = (evidence, targets)
        plan = self._plans.get(key)
        if plan is not None:
            self._plans.move_to_end(key)
            return plan
        plan = self._make_plan(evidence, targets)
        self._plans[key] = plan
        if len(self._plans) > PLAN_CACHE:
            self._plans.popitem(last=False)
        return plan

    def _make_plan(self, evidence: frozenset[int], targets: frozenset[int]) -> QueryPlan:
        comp = self.component
        ev_cliques = {self.home[v] for v in evidence}
        ev_trees = {comp[c] for c in ev_cliques}
        base: dict[int, np.ndarray] = {}
        collect, distribute, roots, tgt = [], [], [], []
        prior_targets = tuple(sorted(v for v in targets if comp[self.home[v]] not in ev_trees))
        for tree in sorted(ev_trees):
            homes = [self.home[v] for v in sorted(targets) if comp[self.home[v]] == tree]
            root = homes[0] if homes else min(c for c in ev_cliques if comp[c] == tree)
            roots.append(root)
            order, parent = _orient(root, self.neighbours)
            below = {c: c in ev_cliques for c in order}  # evidence in the subtree of c
            for c in reversed(order[1:]):
                below[parent[c]] = below[parent[c]] or below[c]
            n_ev = sum(1 for c in ev_cliques if comp[c] == tree)
            inside = {c: int(c in ev_cliques) for c in order}  # evidence cliques in the subtree of c
            for c in reversed(order[1:]):
                inside[parent[c]] += inside[c]
            needed = set()
            for h in homes:
                c = h
                while c is not None and c not in needed:
                    needed.add(c)
                    c = parent[c]
            for c in order:
                if not (below[c] or c in needed):
                    continue
                t = self.potential[c]
                for ch in self.neighbours[c]:
                    if ch != parent[c] and not below[ch]:
                        t = t * self.prior_msg[ch, c].reshape(1, *self._shape_in(ch, c))
                base[c] = t
            for c in reversed(order[1:]):
                if below[c]:
                    shape = (-1, *self._shape_in(c, parent[c]))
                    collect.append((c, parent[c], self._sum_axes(c, parent[c]), shape))
            for c in order[1:]:
                if c in needed:
                    p = parent[c]
                    fresh = inside[c] < n_ev  # evidence outside the subtree of c: a new message
                    distribute.append((p, c, self._sum_axes(p, c), (-1, *self._shape_in(p, c)), fresh))
            for v in sorted(targets):
                h = self.home[v]
                if comp[h] == tree:
                    axes = tuple(1 + i for i, u in enumerate(self.tree.cliques[h]) if u != v)
                    tgt.append((v, h, axes))
        entries = tuple(
            (
                v,
                self.home[v],
                (-1, *(self.cards[v] if u == v else 1 for u in self.tree.cliques[self.home[v]])),
            )
            for v in sorted(evidence)
        )
        return QueryPlan(
            base=base,
            entries=entries,
            collect=tuple(collect),
            distribute=tuple(distribute),
            roots=tuple(roots),
            targets=tuple(tgt),
            prior_targets=prior_targets,
        )

    # ------------------------------------------------------------------ propagation
    def propagate(
        self,
        plan: QueryPlan,
        likelihood: Mapping[int, np.ndarray],
        rows: int,
        normalise: bool = False,
        mass: bool = False,
    ) -> tuple[dict[int, np.ndarray], np.ndarray, np.ndarray | None]:
        """Run ``plan`` with evidence likelihoods, variable → array (rows, card).

        Messages are not rescaled unless ``normalise``; a root mass below :data:`TINY` (or 0, which may be
        an underflow) runs the plan again with every new message normalised to sum 1.

        Returns (marginals, possible, log mass): variable → normalised marginal, shape (rows, card) (NaN in
        impossible rows); whether each row's evidence has probability > 0; with ``mass``, the log of the
        unnormalised probability of the evidence in the trees it touches, shape (rows,), else None.
        """
        reduce = np.add.reduce
        table = dict(plan.base)
        for v, c, shape in plan.entries:
            table[c] = table[c] * likelihood[v].reshape(shape)
        up: dict[int, np.ndarray] = {}
        scales = []
        for c, p, axes, shape in plan.collect:
            m = reduce(table[c], axis=axes)
            if normalise:
                s = reduce(m.reshape(len(m), -1), axis=1)
                s = np.where(s > 0, s, 1.0)
                scales.append(s)
                m = m / s.reshape((-1,) + (1,) * (m.ndim - 1))
            up[c] = m
            table[p] = table[p] * m.reshape(shape)
        z = [reduce(table[r].reshape(len(table[r]), -1), axis=1) for r in plan.roots]
        if not normalise and any(bool((x < TINY).any()) for x in z):
            return self.propagate(plan, likelihood, rows, normalise=True, mass=mass)
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
                    old = self.prior_msg[c, p]
                m = np.divide(m, old, out=np.zeros(m.shape), where=old > 0)
            else:
                m = self.prior_msg[p, c]
            table[c] = table[c] * m.reshape(shape)
        out = {}
        ok = bool(possible.all())
        for v, c, axes in plan.targets:
            m = reduce(table[c], axis=axes)
            if ok:
                m = m / reduce(m, axis=1).reshape(-1, 1)
            else:
                with np.errstate(invalid="ignore", divide="ignore"):
                    m = m / reduce(m, axis=1).reshape(-1, 1)
                m[~possible] = np.nan
            out[v] = m if len(m) == rows else np.broadcast_to(m, (rows, m.shape[1]))
        for v in plan.prior_targets:
            out[v] = np.broadcast_to(self.prior_marginal[v], (rows, self.cards[v]))
        return out, possible, log_mass

    def _likelihoods(
        self,
        hard: Mapping[int, np.ndarray],
        soft: Mapping[int, np.ndarray],
        rows: int,
    ) -> dict[int, np.ndarray]:
        """Likelihood vectors, variable → (rows, card): one-hot rows for hard evidence (ones where a row has
        none, code -1), soft vectors scaled to a largest entry of 1."""
        lik = {}
        for v, codes in hard.items():
            k = self.cards[v]
            m = np.zeros((rows, k))
            on = codes >= 0
            m[np.flatnonzero(on), codes[on]] = 1.0
            m[~on] = 1.0
            lik[v] = m
        for v, q in soft.items():
            top = q.max(axis=1, keepdims=True)
            lik[v] = q / np.where(top > 0, top, 1.0)
        return lik

    def _solve(
        self,
        targets: frozenset[int],
        hard: Mapping[int, np.ndarray],
        soft: Mapping[int, np.ndarray],
        rule: str,
        rows: int,
    ) -> tuple[dict[int, np.ndarray], np.ndarray, np.ndarray]:
        """Marginals of ``targets`` for ``rows`` evidence sets (hard codes and soft distributions per row).

        Returns (marginals, possible, hard_possible): the last is, for rows that are impossible
        only because of the soft evidence, True (the message says so).
        """
        lik = self._likelihoods(hard, soft, rows)
        evidence = frozenset(lik)
        if soft and rule == "jeffrey":
            lik, fit_ok = self._fit_jeffrey(hard, soft, lik, rows)
        else:
            fit_ok = np.ones(rows, dtype=bool)
        out, possible, _ = self.propagate(self.plan(evidence, targets), lik, rows)
        possible &= fit_ok
        hard_possible = np.zeros(rows, dtype=bool)
        if soft and not possible.all():
            # the soft evidence left nothing: is the hard evidence alone possible? If so, rescale each
            # likelihood on the values it allows (a likelihood of 1e-320 is not zero) and answer again
            alone, hp, _ = self.propagate(
                self.plan(frozenset(hard), frozenset(soft)), self._likelihoods(hard, {}, rows), rows
            )
            bad = ~possible & hp
            if bad.any() and rule == "virtual":
                for v, q in soft.items():
                    allowed = alone[v] > 0
                    top = np.where(allowed, q, 0.0).max(axis=1, keepdims=True)
                    lik[v] = np.where(
                        bad[:, None], np.where(allowed, q, 0.0) / np.where(top > 0, top, 1.0), lik[v]
                    )
                out, possible, _ = self.propagate(self.plan(evidence, targets), lik, rows)
            if rule == "virtual":
                hard_possible = ~possible & hp
        return out, possible, hard_possible

    def _fit_jeffrey(
        self,
        hard: Mapping[int, np.ndarray],
        soft: Mapping[int, np.ndarray],
        lik: dict[int, np.ndarray],
        rows: int,
    ) -> tuple[dict[int, np.ndarray], np.ndarray]:
        """Likelihoods that give each soft node its marginal ``q`` (Jeffrey's rule; IPFP for several nodes).

        Returns (likelihoods, ok): ``ok`` is False in rows where ``q`` puts mass on a value the other
        evidence excludes (impossible evidence).
        """
        lik = {**lik, **{v: np.ones((rows, self.cards[v])) for v in soft}}
        evidence = frozenset(lik)
        ok = np.ones(rows, dtype=bool)
        for _ in range(IPFP_MAX_ITER if len(soft) > 1 else 1):
            worst = 0.0
            for v, q in soft.items():
                plan = self.plan(evidence, frozenset([v]))
                marg, possible, _ = self.propagate(plan, lik, rows)
                z = np.where(possible[:, None], marg[v], 0.0)
                ok &= ~((z <= 0) & (q > 0)).any(axis=1) & possible
                if len(soft) > 1:
                    worst = max(worst, float(np.nanmax(np.where(ok[:, None], np.abs(z - q), 0.0))))
                f = np.divide(q, z, out=np.zeros_like(q), where=z > 0)
                new = lik[v] * f
                top = new.max(axis=1, keepdims=True)
                lik[v] = new / np.where(top > 0, top, 1.0)
            if worst < IPFP_TOL:
                break
        return lik, ok

    # ------------------------------------------------------------------ the interface
    def _parse(
        self, evidence: Mapping[str, str | int] | None, soft: SoftEvidence | None, rule: str
    ) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray]]:
        hard = {self.index[n]: np.array([self._value(n, v)]) for n, v in (evidence or {}).items()}
        qs = {}
        if soft:
            check_soft_rule(rule)
            for node, dist in soft.items():
                q = self.soft_vector(node, dist)
                if evidence and node in evidence:
                    raise EvidenceError(f"{node} is given twice: as hard evidence and as soft evidence")
                qs[self.index[node]] = q[None, :]
        return hard, qs

    def _targets(self, targets: Sequence[str] | str) -> list[str]:
        targets = [targets] if isinstance(targets, str) else list(targets)
        for t in targets:
            self._check_node(t)
        return targets

    def query(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, np.ndarray]:
        """See :meth:`InferenceEngine.query <glu.bn.inference.InferenceEngine.query>`."""
        targets = self._targets(targets)
        hard, qs = self._parse(evidence, soft, soft_rule)
        want = frozenset(self.index[t] for t in targets)
        out, possible, hard_possible = self._solve(want, hard, qs, soft_rule, 1)
        if not possible[0]:
            raise self._impossible(evidence, soft, bool(hard_possible[0]))
        return {t: np.array(out[self.index[t]][0]) for t in targets}

    def word_probability_array(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> np.ndarray:
        """P(word = present | evidence) for every binary leaf, shape (n_words,), in ``binary_leaves`` order."""
        if not self.binary_leaves:
            return np.zeros(0)
        res = self.query(list(self.binary_leaves), evidence, soft, soft_rule)
        return np.array([res[w][1] for w in self.binary_leaves])

    def probability_of_evidence(self, evidence: Mapping[str, str | int] | None = None) -> float:
        """P(hard evidence) under the model (0 for impossible evidence)."""
        hard, _ = self._parse(evidence, None, "virtual")
        if not hard:
            return math.prod(self.prior_mass.values())
        _, possible, log_mass = self.propagate(
            self.plan(frozenset(hard), frozenset()), self._likelihoods(hard, {}, 1), 1, mass=True
        )
        trees = {self.component[self.home[v]] for v in hard}
        rest = math.prod(m for t, m in self.prior_mass.items() if t not in trees)
        return float(np.exp(log_mass[0])) * rest if possible[0] else 0.0

    def query_batch(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, Sequence] | None = None,
        soft: Mapping[str, np.ndarray] | None = None,
        soft_rule: SoftRule = "virtual",
        errors: Literal["raise", "nan"] = "raise",
    ) -> dict[str, np.ndarray]:
        """See :meth:`InferenceEngine.query_batch <glu.bn.inference.InferenceEngine.query_batch>`.

        Every row goes through one plan (the nodes observed in any row; a row without a value for one of
        them gets a likelihood of ones there), in chunks of rows of at most :data:`BATCH_ENTRIES` entries.
        """
        targets = self._targets(targets)
        evidence = dict(evidence or {})
        soft = dict(soft or {})
        n = _batch_length(evidence, soft)
        check_soft_rule(soft_rule)
        hard = {self.index[node]: self._codes(node, vals, n) for node, vals in evidence.items()}
        qs = {}
        for node, arr in soft.items():
            self._check_node(node)
            if node in evidence:
                raise EvidenceError(f"{node} is given twice: as hard evidence and as soft evidence")
            arr = np.asarray(arr, dtype=float)
            if arr.ndim != 2 or arr.shape[0] != n:
                raise EvidenceError(f"batch soft evidence on {node} must have shape (n={n}, n_values)")
            for row in arr[: min(n, 1)]:
                self.soft_vector(node, row)
            sums = arr.sum(axis=1)
            if (arr < 0).any() or not np.all(np.abs(sums - 1) <= SUM_TOL):
                bad = int(np.flatnonzero((np.abs(sums - 1) > SUM_TOL) | (arr < 0).any(axis=1))[0])
                self.soft_vector(node, arr[bad])
            qs[self.index[node]] = arr / sums[:, None]
        want = frozenset(self.index[t] for t in targets)
        out = {t: np.full((n, self.cards[self.index[t]]), np.nan) for t in targets}
        size = sum(b.size for b in self.plan(frozenset(hard) | frozenset(qs), want).base.values())
        step = max(1, BATCH_ENTRIES // max(size, 1))
        first_bad = None
        n_bad = 0
        for a in range(0, n, step):
            b = min(n, a + step)
            res, possible, hard_possible = self._solve(
                want,
                {v: c[a:b] for v, c in hard.items()},
                {v: q[a:b] for v, q in qs.items()},
                soft_rule,
                b - a,
            )
            for t in targets:
                out[t][a:b] = res[self.index[t]]
                out[t][a:b][~possible] = np.nan
            if not possible.all():
                n_bad += int((~possible).sum())
                if first_bad is None:
                    k = int(np.flatnonzero(~possible)[0])
                    first_bad = (a + k, bool(hard_possible[k]))
        if errors == "raise" and first_bad is not None:
            i, hp = first_bad
            ev = {
                node: self.bn.schema.values_of(node)[c[i]]
                for node, c in zip(evidence, hard.values(), strict=True)
                if c[i] >= 0
            }
            raise ImpossibleEvidenceError(
                f"row {i}: {self._impossible(ev, {s: None for s in soft}, hp)}"
                + (f" ({n_bad} impossible rows in all)" if n_bad > 1 else "")
            )
        return out


def _components(n: int, neighbours: list[list[int]]) -> list[int]:
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


def _orient(root: int, neighbours: list[list[int]]) -> tuple[list[int], dict[int, int | None]]:
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
