"""The junction tree engine: exact inference in any discrete network, vectorised over evidence sets.

:class:`JunctionTreeEngine` answers the queries of :class:`~glu.bn.inference.InferenceEngine` on the
junction tree that :mod:`glu.bn.plan` finds (its size is checked against the limit before any table is
built). It uses the Hugin architecture on tables whose last axis is the rows — one row for a single query,
``n`` for ``n`` evidence sets in one batch (messages are rescaled only when the evidence is improbable enough
for them to underflow, :mod:`glu.bn.propagation`):

1. once per network: each clique's table, the product of the CPTs assigned to it; the messages of the
   network without evidence along every edge, in both directions; the marginal of every node;
2. once per *evidence pattern* (which nodes carry evidence, which nodes are asked for; a cached
   :class:`~glu.bn.propagation.QueryPlan`): a root (a clique of a target), which cliques must send a new
   message (those below which there is evidence) and which must receive one (those on the way to a
   target's clique), and for every other edge the message without evidence, multiplied into the tables
   in advance;
3. per query: evidence enters as likelihood vectors (one-hot for hard evidence, ``q`` for virtual
   evidence) in one clique each, the new messages flow to the root and out to the targets' cliques, and
   each target's marginal is summed out of its smallest clique (:func:`glu.bn.propagation.propagate`).

A batch (:mod:`glu.bn.junction_batch`) whose rows share a pattern is instead planned on the network
conditioned on it — barren nodes left out, observed nodes sliced out of the tables
(:mod:`glu.bn.conditioned`) — which shrinks the tables every row costs.

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

import numpy as np

from glu.bn.conditioned import ConditionedPlan, NetworkArrays, conditioned_plan
from glu.bn.inference import IPFP_MAX_ITER, IPFP_TOL, InferenceEngine, Method, SoftEvidence
from glu.bn.junction_batch import JunctionBatch
from glu.bn.model import BayesNet
from glu.bn.plan import JunctionTreePlan, plan_junction_tree
from glu.bn.propagation import QueryPlan, components, orient, paths_to, propagate
from glu.bn.soft import SoftRule, check_soft_rule
from glu.errors import EvidenceError, ModelError

PLAN_CACHE = 64
"""Query plans kept per engine (one per evidence pattern and set of targets), the most recently used …"""
PLAN_CACHE_ENTRIES = 1 << 25
"""… as long as their tables hold at most this many entries together (256 MiB)."""
CONDITION_ROWS = 32
"""Rows of a batch that share an evidence pattern from which the engine plans for the pattern
(:mod:`glu.bn.conditioned`) instead of using the network's one junction tree."""


class JunctionTreeEngine(JunctionBatch, InferenceEngine, method="junction"):
    """Exact inference in any discrete :class:`BayesNet` by junction tree propagation (see the module
    docstring).

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
        self.component = components(len(cliques), self.neighbours)
        self.home = [
            min((c for c, cl in enumerate(cliques) if v in cl), key=self._clique_size)
            for v in range(len(nodes))
        ]
        """The smallest clique of each variable: where its evidence enters and its marginal is read."""
        self.potential = [np.ones((*(self.cards[v] for v in cl), 1)) for cl in cliques]
        for n in nodes:
            family = [self.index[p] for p in bn.parents[n]] + [self.index[n]]
            fam = set(family)
            c = min((k for k, cl in enumerate(cliques) if fam <= set(cl)), key=self._clique_size)
            perm = np.argsort(family)
            table = np.transpose(bn.cpts[n], perm)
            shape = [self.cards[v] if v in fam else 1 for v in cliques[c]]
            self.potential[c] = self.potential[c] * table.reshape(*shape, 1)
        self._prior_messages()
        self._plans: OrderedDict[tuple, QueryPlan | ConditionedPlan] = OrderedDict()
        self._max_table = max_table
        self._arrays: NetworkArrays | None = None
        self.condition_rows = CONDITION_ROWS
        """Rows sharing a pattern from which a batch is planned per pattern (tests set it to force either
        way)."""

    def _clique_size(self, c: int) -> tuple[int, int]:
        return self.tree.size(self.tree.cliques[c]), c

    # ------------------------------------------------------------------ structure helpers
    def _sum_axes(self, a: int, b: int) -> tuple[int, ...]:
        """Axes of clique ``a``'s table (rows last) summed out for the message to clique ``b``."""
        sep = set(self.tree.cliques[b])
        return tuple(i for i, v in enumerate(self.tree.cliques[a]) if v not in sep)

    def _shape_in(self, a: int, b: int) -> tuple[int, ...]:
        """The shape (without rows) of a message from ``a`` broadcast over clique ``b``'s table."""
        sep = set(self.tree.cliques[a])
        return tuple(self.cards[v] if v in sep else 1 for v in self.tree.cliques[b])

    def _prior_messages(self) -> None:
        """Messages of the network without evidence along every directed edge, and every node's marginal."""
        cliques = self.tree.cliques
        self.prior_msg: dict[tuple[int, int], np.ndarray] = {}
        for root in sorted(set(self.component)):
            order, parent = orient(root, self.neighbours)
            for c in reversed(order[1:]):  # collect, children first
                t = self.potential[c]
                for ch in self.neighbours[c]:
                    if ch != parent[c]:
                        t = t * self.prior_msg[ch, c].reshape(*self._shape_in(ch, c), 1)
                p = parent[c]
                self.prior_msg[c, p] = t.sum(axis=self._sum_axes(c, p))
            for c in order:  # distribute, parents first: the product of every other incoming message
                for ch in self.neighbours[c]:
                    if ch == parent[c]:
                        continue
                    t = self.potential[c]
                    for nb in self.neighbours[c]:
                        if nb != ch:
                            t = t * self.prior_msg[nb, c].reshape(*self._shape_in(nb, c), 1)
                    self.prior_msg[c, ch] = t.sum(axis=self._sum_axes(c, ch))
        self.prior_mass: dict[int, float] = {}
        self.prior_marginal: list[np.ndarray] = []
        full = []
        for c in range(len(cliques)):
            t = self.potential[c]
            for nb in self.neighbours[c]:
                t = t * self.prior_msg[nb, c].reshape(*self._shape_in(nb, c), 1)
            full.append(t)
            self.prior_mass.setdefault(self.component[c], float(t.sum()))
        for v, h in enumerate(self.home):
            axes = tuple(i for i, u in enumerate(cliques[h]) if u != v)
            m = full[h].sum(axis=axes)[:, 0]
            total = m.sum()
            self.prior_marginal.append(m / total if total > 0 else np.full(m.shape, np.nan))

    def _cached(self, key: tuple, make) -> QueryPlan | ConditionedPlan:  # type: ignore[no-untyped-def]
        plan = self._plans.get(key)
        if plan is not None:
            self._plans.move_to_end(key)
            return plan
        plan = make()
        self._plans[key] = plan

        def entries(p: QueryPlan | ConditionedPlan | None) -> int:
            if p is None:
                return 0
            return (p.plan if isinstance(p, ConditionedPlan) else p).size

        while len(self._plans) > 1 and (
            len(self._plans) > PLAN_CACHE
            or sum(entries(p) for p in self._plans.values()) > PLAN_CACHE_ENTRIES
        ):
            self._plans.popitem(last=False)
        return plan

    def plan(self, evidence: frozenset[int], targets: frozenset[int]) -> QueryPlan:
        """The plan on the network's junction tree for evidence on ``evidence`` and marginals of ``targets``
        (variable indices), cached."""
        return self._cached(("tree", evidence, targets), lambda: self._make_plan(evidence, targets))  # type: ignore[return-value]

    def conditioned(
        self, observed: frozenset[int], soft: frozenset[int], targets: frozenset[int]
    ) -> ConditionedPlan | None:
        """The plan of the network conditioned on ``observed`` (:mod:`glu.bn.conditioned`), cached; None
        if its tables would pass the size limit (the network's junction tree answers instead)."""
        if self._arrays is None:
            self._arrays = NetworkArrays.of(self.bn)
        arrays = self._arrays

        def make() -> ConditionedPlan | None:
            try:
                return conditioned_plan(arrays, observed, soft, targets, self._max_table)
            except ModelError:
                return None

        return self._cached(("conditioned", observed, soft, targets), make)  # type: ignore[return-value]

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
            order, parent = orient(root, self.neighbours)
            below = {c: c in ev_cliques for c in order}  # evidence in the subtree of c
            for c in reversed(order[1:]):
                below[parent[c]] = below[parent[c]] or below[c]
            n_ev = sum(1 for c in ev_cliques if comp[c] == tree)
            inside = {c: int(c in ev_cliques) for c in order}  # evidence cliques in the subtree of c
            for c in reversed(order[1:]):
                inside[parent[c]] += inside[c]
            needed = paths_to(order, parent, homes)
            for c in order:
                if not (below[c] or c in needed):
                    continue
                t = self.potential[c]
                for ch in self.neighbours[c]:
                    if ch != parent[c] and not below[ch]:
                        t = t * self.prior_msg[ch, c].reshape(*self._shape_in(ch, c), 1)
                base[c] = t
            for c in reversed(order[1:]):
                if below[c]:
                    shape = (*self._shape_in(c, parent[c]), -1)
                    collect.append((c, parent[c], self._sum_axes(c, parent[c]), shape))
            for c in order[1:]:
                if c in needed:
                    p = parent[c]
                    fresh = inside[c] < n_ev  # evidence outside the subtree of c: a new message
                    distribute.append((p, c, self._sum_axes(p, c), (*self._shape_in(p, c), -1), fresh))
            for v in sorted(targets):
                h = self.home[v]
                if comp[h] == tree:
                    axes = tuple(i for i, u in enumerate(self.tree.cliques[h]) if u != v)
                    tgt.append((v, h, axes))
        entries = tuple(
            (
                v,
                self.home[v],
                (*(self.cards[v] if u == v else 1 for u in self.tree.cliques[self.home[v]]), -1),
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
            prior={v: self.prior_marginal[v] for v in prior_targets},
            messages=self.prior_msg,
        )

    # ------------------------------------------------------------------ propagation
    def _run(
        self,
        targets: frozenset[int],
        hard: Mapping[int, np.ndarray],
        likelihood: Mapping[int, np.ndarray],
        rows: int,
        mass: bool = False,
    ) -> tuple[dict[int, np.ndarray], np.ndarray, np.ndarray | None]:
        """Marginals of ``targets`` given hard codes (variable → (rows,), -1 = not observed in that row) and
        soft likelihoods (variable → (rows, k)), by the best plan: conditioned on the pattern for a batch of
        at least :attr:`condition_rows` rows that all observe the same nodes, else the network's tree.

        Returns (marginals, possible, log mass) as :func:`glu.bn.propagation.propagate`.
        """
        if (
            not mass
            and rows >= self.condition_rows
            and hard
            and all(bool((c >= 0).all()) for c in hard.values())
        ):
            cp = self.conditioned(frozenset(hard), frozenset(likelihood), targets)
            if cp is not None:
                entries, const = cp.entries(hard, likelihood, rows)
                out, possible, _ = propagate(cp.plan, entries, rows)
                possible = possible & (const > 0)
                for v in targets:
                    if v in hard:
                        m = np.zeros((rows, self.cards[v]))
                        m[np.arange(rows), hard[v]] = 1.0
                        out[v] = m
                    if not possible.all():
                        out[v] = np.array(out[v], dtype=float)
                        out[v][~possible] = np.nan
                return out, possible, None
        lik = {**self._one_hot(hard, rows), **likelihood}
        plan = self.plan(frozenset(lik), targets)
        entries = [(c, lik[v].T.reshape(shape)) for v, c, shape in plan.entries]
        return propagate(plan, entries, rows, mass=mass)

    def _one_hot(self, hard: Mapping[int, np.ndarray], rows: int) -> dict[int, np.ndarray]:
        """Hard evidence as likelihood vectors, variable → (rows, k): one-hot (ones where code -1)."""
        lik = {}
        for v, codes in hard.items():
            m = np.zeros((rows, self.cards[v]))
            on = codes >= 0
            m[np.flatnonzero(on), codes[on]] = 1.0
            m[~on] = 1.0
            lik[v] = m
        return lik

    @staticmethod
    def _scaled(soft: Mapping[int, np.ndarray]) -> dict[int, np.ndarray]:
        """Soft distributions as likelihoods scaled to a largest entry of 1 per row."""
        out = {}
        for v, q in soft.items():
            top = q.max(axis=1, keepdims=True)
            out[v] = q / np.where(top > 0, top, 1.0)
        return out

    def _solve(
        self,
        targets: frozenset[int],
        hard: Mapping[int, np.ndarray],
        soft: Mapping[int, np.ndarray],
        rule: str,
        rows: int,
    ) -> tuple[dict[int, np.ndarray], np.ndarray, np.ndarray]:
        """Marginals of ``targets`` for ``rows`` evidence sets (hard codes and soft distributions per row).

        Returns (marginals, possible, hard_possible): the last is True in rows that are impossible only
        because of virtual evidence (the message says so).
        """
        if soft and rule == "jeffrey":
            lik, fit_ok = self._fit_jeffrey(hard, soft, rows)
        else:
            lik, fit_ok = self._scaled(soft), np.ones(rows, dtype=bool)
        out, possible, _ = self._run(targets, hard, lik, rows)
        possible = possible & fit_ok
        hard_possible = np.zeros(rows, dtype=bool)
        if soft and rule == "virtual" and not possible.all():
            # the soft evidence left nothing: is the hard evidence alone possible? If so, rescale each
            # likelihood on the values it allows (a likelihood of 1e-320 is not zero) and answer again
            alone, hp, _ = self._run(frozenset(soft), hard, {}, rows)
            bad = ~possible & hp
            if bad.any():
                for v, q in soft.items():
                    allowed = alone[v] > 0
                    top = np.where(allowed, q, 0.0).max(axis=1, keepdims=True)
                    rescaled = np.where(allowed, q, 0.0) / np.where(top > 0, top, 1.0)
                    lik[v] = np.where(bad[:, None], rescaled, lik[v])
                out, possible, _ = self._run(targets, hard, lik, rows)
            hard_possible = ~possible & hp
        return out, possible, hard_possible

    def _fit_jeffrey(
        self, hard: Mapping[int, np.ndarray], soft: Mapping[int, np.ndarray], rows: int
    ) -> tuple[dict[int, np.ndarray], np.ndarray]:
        """Likelihoods that give each soft node its marginal ``q`` (Jeffrey's rule; IPFP for several nodes).

        Returns (likelihoods, ok): ``ok`` is False in rows where ``q`` puts mass on a value the other
        evidence excludes (impossible evidence).
        """
        lik = {v: np.ones((rows, self.cards[v])) for v in soft}
        ok = np.ones(rows, dtype=bool)
        for _ in range(IPFP_MAX_ITER if len(soft) > 1 else 1):
            worst = 0.0
            for v, q in soft.items():
                marg, possible, _ = self._run(frozenset([v]), hard, lik, rows)
                z = np.where(possible[:, None], marg[v], 0.0)
                ok &= ~((z <= 0) & (q > 0)).any(axis=1) & possible
                if len(soft) > 1:
                    worst = max(worst, float(np.max(np.where(ok[:, None], np.abs(z - q), 0.0))))
                new = lik[v] * np.divide(q, z, out=np.zeros_like(q), where=z > 0)
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
        return {t: np.clip(np.array(out[self.index[t]][0]), 0.0, 1.0) for t in targets}  # rounding past 1

    def probability_of_evidence(self, evidence: Mapping[str, str | int] | None = None) -> float:
        """P(hard evidence) under the model (0 for impossible evidence)."""
        hard, _ = self._parse(evidence, None, "virtual")
        if not hard:
            return math.prod(self.prior_mass.values())
        _, possible, log_mass = self._run(frozenset(), hard, {}, 1, mass=True)
        trees = {self.component[self.home[v]] for v in hard}
        rest = math.prod(m for t, m in self.prior_mass.items() if t not in trees)
        return float(np.exp(log_mass[0])) * rest if possible[0] else 0.0
