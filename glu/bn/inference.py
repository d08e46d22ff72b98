"""Exact inference in any discrete Bayesian network: one query interface, declared once.

``make_engine(bn)`` answers queries about a :class:`~glu.bn.model.BayesNet` — GLU's Affordance–Words
network, a network learned from a lab's own schema, or one imported from BIF, XMLBIF or UAI. Every engine
is one :class:`Engine` — the evidence, relevance, soft rules, batches, caches and labelled results,
written once — over the array arithmetic that suits the network's shape (its *backend*, a
:class:`typing.Protocol`):

:class:`~glu.bn.core.CoreBackend` (``method="core"``)
    for networks shaped like GLU's: a small *core* (the affordance nodes and every node with children)
    whose joint table fits in memory, and *leaves* (the words) hanging off it — microseconds a query.
:class:`~glu.bn.junction.JunctionBackend` (``method="junction"``)
    for any other network: junction trees planned per evidence pattern from the tables the query needs,
    with the observed nodes conditioned out; a plan keeps its messages between single queries.

``method="auto"`` (the default) takes the core when its tables are small (:data:`CORE_MAX_STATES`,
:data:`CORE_MAX_ENTRIES`), else the junction tree. Both give the same posteriors (the tests compare them
with each other, with pgmpy, with pyAgrum and with brute-force enumeration).

Each query, in order:

1. **relevance** (:mod:`glu.bn.relevance`, cached per evidence pattern): a target that no evidence can reach
   (d-separated from all of it) is answered from the engine's cached prior marginals; for the others, only
   the tables of the nodes the answer needs and the evidence that can change it are used — barren and
   d-separated nodes are left out, as in pyAgrum's relevance reasoning. Evidence that could have
   probability 0 (a zero in a table above it, or all-zero rows in the network) is still checked: a single
   query's hard evidence is first shown possible, where it can be, by a configuration of positive
   probability that agrees with it (:func:`~glu.bn.relevance.surely_possible`, a compiled search of a few
   microseconds) and then uses the relevance above; otherwise its query is answered from every table
   above the targets and the evidence (barren nodes left out, so the same propagation gives
   P(evidence)); when no target needs computing, P(evidence) alone is computed (on the evidence's
   ancestors), and a single query remembers whether those values are possible.
2. **soft evidence** becomes likelihoods (:mod:`glu.bn.soft`, the one home of both rules);
3. the **backend** computes the marginals of the remaining targets, for one row (a single query) or many
   (a batch: rows grouped by which nodes they observe, identical rows answered once by a one-dimensional
   mixed-radix key of their values).

Evidence, for every engine:

* hard evidence on any node: ``{"Action": "tap", "rolls": "present"}`` (value names, aliases or indices);
* soft evidence on any node, a distribution ``q`` over its values, entered either as *virtual*
  (likelihood) evidence, ``p(X | e) ∝ Σ_a p(X, a | e) q(a)`` — the originals' soft fusion — or by
  *Jeffrey's rule*, which makes the node's posterior marginal equal to ``q``:
  ``p(X | e) = Σ_a p(X | e, A=a) q(a)`` (several Jeffrey nodes: iterative proportional fitting);
* evidence of probability 0 raises :class:`~glu.errors.ImpossibleEvidenceError` naming it;
* many evidence sets at once: :meth:`Engine.query_batch` (arrays) and :meth:`Engine.posterior_table`.

Results come in two forms: the numeric ones (:meth:`~Engine.query`, :meth:`~Engine.query_batch`,
:meth:`~Engine.word_probability_array`: NumPy arrays in the nodes' value order) and the labelled ones
(:meth:`~Engine.posterior`, :meth:`~Engine.posteriors`, :meth:`~Engine.marginals`,
:meth:`~Engine.posterior_table`, :meth:`~Engine.word_probabilities`: pandas objects indexed by value and
word names, each node's index made once).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, Protocol

import numpy as np

from glu.bn.core import CoreBackend, core_size, core_split
from glu.bn.junction import JunctionBackend
from glu.bn.labels import Labels, series
from glu.bn.model import BayesNet
from glu.bn.network import NetworkArrays, code_of
from glu.bn.parse import SoftEvidence, Values, batch_length
from glu.bn.relevance import reachable, requisite, surely_possible
from glu.bn.soft import SoftRule, check_soft_rule, fit_jeffrey, virtual_likelihood
from glu.errors import EvidenceError, ModelError

if TYPE_CHECKING:
    import pandas as pd

Method = Literal["auto", "core", "junction"]
METHODS: tuple[str, ...] = ("auto", "core", "junction")
CORE_MAX_STATES = 1 << 16
"""``method="auto"`` takes the core engine only if the core's joint table has at most this many states …"""
CORE_MAX_ENTRIES = 1 << 22
"""… and its leaf tables over the core (states × (leaf values + 2)) at most this many entries."""
PATTERN_CACHE = 4096
"""Evidence patterns whose relevance an engine keeps (then it starts again)."""
SUBNORMAL_RISK = 1e-200
"""A virtual likelihood with a positive entry below this (after scaling) is rescaled on the allowed values."""
POSSIBLE_MEMO = 1 << 16
"""Single evidence sets whose probability (0 or not) an engine remembers (then it starts again)."""
BATCH_ENTRIES = 1 << 22
"""A batch is answered in chunks of rows whose tables hold at most this many entries together (32 MiB)."""

Array = np.ndarray
Answer = tuple[dict[int, Array], Array]
_ONE, _NONE = np.ones(1, dtype=bool), np.zeros(1, dtype=bool)  # a single query's possible: never written to
_ONE.flags.writeable = _NONE.flags.writeable = False
_AUTO: weakref.WeakKeyDictionary[BayesNet, str] = weakref.WeakKeyDictionary()
"""The engine that suits each live network (a frozen network: chosen once, :func:`choose_method`)."""
_PARTS: weakref.WeakKeyDictionary[BayesNet, tuple[Values, Labels, tuple[str, ...]]]
_PARTS = weakref.WeakKeyDictionary()
"""What every engine of a live network shares, made once (:class:`Engine`): the value look-up, the labels, and
the word nodes (leaves that are not affordance nodes, with two values)."""


def choose_method(bn: BayesNet, method: str = "auto") -> str:
    """``"core"`` or ``"junction"``: the engine ``method`` asks for, or the one that suits ``bn`` (auto)."""
    if method not in METHODS:
        raise ModelError(f"unknown inference method {method!r}; allowed: {', '.join(METHODS)}")
    if method != "auto":
        return method
    chosen = _AUTO.get(bn)
    if chosen is None:
        states, entries = core_size(bn)
        small = len(core_split(bn)[0]) <= 60 and states <= CORE_MAX_STATES and entries <= CORE_MAX_ENTRIES
        chosen = _AUTO[bn] = "core" if small else "junction"
    return chosen


class Backend(Protocol):
    """The array arithmetic under an engine: :class:`~glu.bn.core.CoreBackend` or
    :class:`~glu.bn.junction.JunctionBackend`. Variables are node indices; hard and likelihood mappings
    come with sorted keys; a single query is a batch of one row (its hard evidence Python ints, a batch's
    arrays of codes, shape (rows,))."""

    method: str

    def solve(
        self, targets: Sequence[int], hard: Mapping[int, Array], likelihood: Mapping[int, Array], rows: int,
        tables: frozenset[int],
    ) -> Answer:  # fmt: skip
        """The marginals of ``targets`` and whether each row's evidence is possible
        (:meth:`glu.bn.core.CoreBackend.solve`).

        ``hard``: variable → value codes, shape (rows,); ``likelihood``: variable → shape (rows, k). Returns
        (target → shape (rows, k), NaN where impossible; possible, bool, shape (rows,)).
        """

    def size(self, tables: frozenset[int], observed: Sequence[int], soft: Sequence[int], targets: Sequence[int]) -> int:  # fmt: skip # noqa: E501
        """Table entries one row of this pattern costs (to cut a batch into chunks)."""

    def log_mass(self, hard: Mapping[int, Array], rows: int) -> Array:
        """log P(hard evidence), shape (rows,) (-inf: probability 0)."""


def make_engine(bn: BayesNet, method: Method = "auto", max_table: int | None = None) -> Engine:
    """The exact inference engine of ``bn``.

    Parameters
    ----------
    bn : the network
    method : ``"auto"`` (default: the core for GLU-shaped networks, else the junction tree), ``"core"`` or
        ``"junction"``
    max_table : the largest table the junction tree may build (entries); None: ``$GLU_MAX_TABLE`` or
        :data:`glu.bn.plan.MAX_TABLE_DEFAULT`. A query whose tables would pass it is refused in one line
        (the largest table and the elimination width).

    Raises
    ------
    ModelError
        an unknown method, or a core engine forced on a network whose core does not fit

    Examples
    --------
    On glu's synthetic data (the real data gives the GLU 2017 bars):

    >>> from glu.bn import learn_bn
    >>> from glu.data import load_experiments
    >>> eng = make_engine(learn_bn(load_experiments("synthetic")))
    >>> p = eng.query(["ObjVel"], {"Action": "tap", "Shape": "sphere", "Size": "small"})["ObjVel"]
    >>> p.round(3)                                                      # slow, medium, fast
    array([0.015, 0.121, 0.863])
    >>> eng.method, isinstance(eng, Engine)
    ('core', True)
    """
    kind = choose_method(bn, method)
    net = NetworkArrays.of(bn)
    backend: Backend = CoreBackend(bn) if kind == "core" else JunctionBackend(net, max_table)
    return Engine(bn, net, backend)


def _with_nan(out: dict[int, Array], possible: Array) -> dict[int, Array]:
    """Copies of the marginals ``out`` with NaN in the rows that are not ``possible``."""
    out = {t: np.array(m, dtype=float) for t, m in out.items()}
    for m in out.values():
        m[~possible] = np.nan
    return out


def _row_key(hard: Mapping[int, int | Array]) -> tuple[int, ...]:
    """One row of hard evidence as a key of the engine's memo of possible evidence: nodes, then codes."""
    return (*hard, *map(code_of, hard.values()))


@dataclass(frozen=True)
class Relevance:
    """What one evidence pattern needs (:meth:`Engine._relevance`): targets answered from their
    observed value, from the cached priors, or by the backend — with the evidence and tables it needs; and
    whether the hard evidence must be checked for probability 0 apart (``check``: no target is computed)."""

    observed: tuple[int, ...]
    prior: tuple[int, ...]
    targets: tuple[int, ...]
    hard: tuple[int, ...]
    soft: tuple[int, ...]
    tables: frozenset[int]
    check: bool


class Engine:
    """The query interface of every network: evidence, relevance, soft rules, batches and caches over a
    backend's arithmetic (see the module docstring). Made by :func:`make_engine`.

    Attributes
    ----------
    bn : the network
    nodes : its node names
    method : ``"core"`` or ``"junction"``, the backend's
    binary_leaves : the word nodes: leaves with two values that are not affordance nodes
    backend : the array arithmetic (:class:`~glu.bn.core.CoreBackend` — the core's joint tables, which
        :func:`glu.bn.sampling.sample` draws from — or :class:`~glu.bn.junction.JunctionBackend`)
    deduplicate : answer identical rows of a batch once (benchmarks turn it off to time every row)
    """

    def __init__(self, bn: BayesNet, net: NetworkArrays, backend: Backend) -> None:
        self.bn = bn
        self.nodes = bn.nodes
        self.net = net
        self.backend = backend
        self.method = backend.method
        parts = _PARTS.get(bn)
        if parts is None:  # the word nodes: leaves that are not affordance nodes, with two values
            aff = set(bn.schema.affordance_nodes)
            nodes = zip(bn.nodes, net.children, net.cards, strict=True)
            leaves = tuple(n for n, kids, k in nodes if not kids and k == 2 and n not in aff)
            parts = _PARTS[bn] = (Values(bn), Labels(bn.schema.values_of), leaves)
        self.values, self.labels, self.binary_leaves = parts
        self.deduplicate = True
        self._relevant: dict[tuple, Relevance] = {}
        self._priors: dict[int, Array] = {}
        self._possible_memo: dict[tuple, Array] = {}

    def junction_tree(self):  # type: ignore[no-untyped-def]
        """The junction tree of the whole network (:class:`~glu.bn.plan.JunctionTreePlan`), planned once."""
        backend = self.backend if isinstance(self.backend, JunctionBackend) else JunctionBackend(self.net)
        return backend.junction_tree()

    def soft_vector(self, node: str, dist: Mapping[str, float] | Sequence[float] | np.ndarray) -> np.ndarray:
        """Soft evidence on ``node`` checked and returned as a vector over its values, shape (k,)."""
        return self.values.soft_vector(node, dist)

    # ------------------------------------------------------------------ relevance and priors
    def _relevance(
        self, hard: tuple[int, ...], soft: tuple[int, ...], targets: tuple[int, ...], sure: bool = False
    ) -> Relevance:
        """What the pattern needs; ``sure``: its evidence is known to be possible (:func:`surely_possible`),
        so that tables with zeros do not keep the evidence that cannot reach the targets."""
        key = (hard, soft, targets, sure)
        rel = self._relevant.get(key)
        if rel is not None:
            return rel
        net = self.net
        hard_set, soft_set = set(hard), set(soft)
        virtual = soft_set | net.inexact
        rest = [t for t in targets if t not in hard_set]
        need = None
        if len(rest) == 1 and (hard_set or virtual):  # one target: its ball tells whether evidence reaches it
            need = requisite(net.parents, net.children, hard_set, virtual, rest)
            reach = set(rest) if need.hard or need.virtual else set()
        else:
            reach = reachable(net.parents, net.children, hard_set, virtual) if hard_set or virtual else set()
        computed = tuple(sorted({t for t in rest if t in reach}))
        risky = not sure and self._risky(hard, soft)
        if computed and risky:  # every table above the targets and the evidence: exact, and P(evidence) too
            tables, hard_used, soft_used = net.ancestors({*computed, *hard, *soft, *net.inexact}), hard, soft
        elif computed:  # Bayes-ball: barren and d-separated nodes left out, and the evidence they carry
            if need is None:
                need = requisite(net.parents, net.children, hard_set, virtual, computed)
            tables, hard_used = need.tables, tuple(sorted(need.hard))
            soft_used = tuple(sorted(need.virtual & soft_set))
        else:
            tables, hard_used, soft_used = set(), (), ()
        rel = Relevance(
            observed=tuple(t for t in targets if t in hard_set),
            prior=tuple(t for t in rest if t not in reach),
            targets=computed,
            hard=hard_used,
            soft=soft_used,
            tables=frozenset(tables),
            check=risky and not computed and bool(hard),
        )
        if len(self._relevant) >= PATTERN_CACHE:
            self._relevant.clear()
        self._relevant[key] = rel
        return rel

    def _risky(self, hard: tuple[int, ...], soft: tuple[int, ...]) -> bool:
        """Whether evidence on these nodes may have probability 0: a zero in a table above it, or all-zero
        rows anywhere (then its probability is checked)."""
        net, zero = self.net, self.net.zero_above
        return bool(hard or soft) and (bool(net.inexact) or any(zero[v] for v in (*hard, *soft)))

    def _possible(self, hard: dict[int, Array], rows: int) -> Array:
        """Whether each row's hard evidence has probability > 0, shape (rows,) (single queries remembered)."""
        if rows > 1:
            return self.backend.log_mass(hard, rows) > -np.inf
        key = _row_key(hard)
        ok = self._possible_memo.get(key)
        return self._remember(key, self.backend.log_mass(hard, 1) > -np.inf) if ok is None else ok

    def _remember(self, key: tuple, ok: Array) -> Array:
        """Keep ``ok`` as the possibility of the evidence ``key`` (:data:`POSSIBLE_MEMO` at most)."""
        if len(self._possible_memo) >= POSSIBLE_MEMO:
            self._possible_memo.clear()
        self._possible_memo[key] = ok
        return ok

    def _shown_possible(self, hard: dict[int, Array]) -> bool:
        """Whether one row's hard evidence is known to have probability > 0: remembered, or shown by
        :func:`surely_possible` (then remembered); False: not known (it may still be possible)."""
        if self.net.inexact:  # all-zero rows: a configuration of positive terms is not a positive mass
            return False
        key = _row_key(hard)
        ok = self._possible_memo.get(key)
        if ok is not None:
            return bool(ok[0])
        return surely_possible(self.net, hard) and bool(self._remember(key, _ONE)[0])

    def _prior(self, targets: Sequence[int]) -> list[Array]:
        """Prior marginals (given only the all-zero rows, if any), computed once per node."""
        missing = tuple(sorted({t for t in targets if t not in self._priors}))
        if missing:
            net = self.net
            need = requisite(net.parents, net.children, (), net.inexact, missing)
            out, _ = self.backend.solve(missing, {}, {}, 1, need.tables)
            for t in missing:
                self._priors[t] = np.array(out[t][0])
        return [self._priors[t] for t in targets]

    # ------------------------------------------------------------------ the arithmetic, once
    def _solve(
        self, targets: tuple[int, ...], hard: dict[int, Array], lik: dict[int, Array], rows: int
    ) -> Answer:
        """Marginals of ``targets`` (rows, k) and possible (rows,), given hard codes and likelihoods (sorted
        keys), by relevance, then the backend in chunks of at most :data:`BATCH_ENTRIES` table entries."""
        keys = tuple(hard)
        # one row of hard evidence shown possible needs no table kept to check it (tables with zeros)
        sure = rows == 1 and not lik and self._risky(keys, ()) and self._shown_possible(hard)
        rel = self._relevance(keys, tuple(lik), targets, sure)
        out: dict[int, Array] = {}
        possible = _ONE if rows == 1 else np.ones(rows, dtype=bool)
        if rel.targets:
            h = {v: hard[v] for v in rel.hard}
            s = {v: lik[v] for v in rel.soft}
            solve = self.backend.solve
            step = rows
            if rows > 1:
                size = self.backend.size(rel.tables, rel.hard, rel.soft, rel.targets)
                step = max(1, BATCH_ENTRIES // max(size, 1))
            if rows <= step:
                res, possible = solve(rel.targets, h, s, rows, rel.tables)
                out = dict(res)  # the backend may keep its answer: never written into
            else:
                out = {t: np.empty((rows, self.net.cards[t])) for t in rel.targets}
                for a in range(0, rows, step):
                    b = min(rows, a + step)
                    res, possible[a:b] = solve(
                        rel.targets, {v: c[a:b] for v, c in h.items()}, {v: q[a:b] for v, q in s.items()},
                        b - a, rel.tables,
                    )  # fmt: skip
                    for t in rel.targets:
                        out[t][a:b] = res[t]
        for t in rel.observed:
            m = np.zeros((rows, self.net.cards[t]))
            m[np.arange(rows), hard[t]] = 1.0
            out[t] = m
        if rel.prior:
            for t, p in zip(rel.prior, self._prior(rel.prior), strict=True):
                out[t] = p[None, :] if rows == 1 else np.broadcast_to(p, (rows, len(p)))
        if rel.check:  # no target computed, and hard evidence that may have probability 0: its probability
            possible = possible & self._possible(hard, rows)
        if not (possible[0] if rows == 1 else possible.all()):
            out = _with_nan(out, possible)
        return out, possible

    def _answer(
        self, targets: tuple[int, ...], hard: dict[int, Array], soft: dict[int, Array], rule: str, rows: int
    ) -> tuple[dict[int, Array], Array, Array]:
        """:meth:`_solve` with soft distributions (rows, k) turned into likelihoods by ``rule``; returns
        (marginals, possible, hard_possible: rows impossible only because of the virtual evidence)."""
        hard_possible = _NONE if rows == 1 else np.zeros(rows, dtype=bool)
        if not soft:
            out, possible = self._solve(targets, hard, {}, rows)
            return out, possible, hard_possible
        if rule == "jeffrey":
            lik, fit_ok = fit_jeffrey(
                soft, lambda v, lam: self._solve((v,), hard, dict(sorted(lam.items())), rows)[0][v]
            )
            out, possible = self._solve(targets, hard, lik, rows)
            if not fit_ok.all():
                possible = possible & fit_ok
                out = _with_nan(out, possible)
            return out, possible, hard_possible
        lik = {v: virtual_likelihood(q) for v, q in soft.items()}
        if any(((lam > 0) & (lam < SUBNORMAL_RISK)).any() for lam in lik.values()):
            # a likelihood this small may end in subnormal numbers: scale it on the values the hard evidence
            # allows, so that its largest allowed entry is 1
            alone, _ = self._solve(tuple(soft), hard, {}, rows)
            lik = {v: virtual_likelihood(q, alone[v] > 0) for v, q in soft.items()}
        out, possible = self._solve(targets, hard, lik, rows)
        if not possible.all():
            # the soft evidence left nothing: is the hard evidence alone possible? If so, rescale each
            # likelihood on the values it allows (a likelihood of 1e-320 is not zero) and answer again
            alone, hp = self._solve(tuple(soft), hard, {}, rows)
            bad = ~possible & hp
            if bad.any():
                for v, q in soft.items():
                    lik[v] = np.where(bad[:, None], virtual_likelihood(q, alone[v] > 0), lik[v])
                out, possible = self._solve(targets, hard, lik, rows)
            hard_possible = ~possible & hp
        return out, possible, hard_possible

    # ------------------------------------------------------------------ single queries
    def _variables(self, targets: Sequence[str] | str) -> tuple[list[str], tuple[int, ...]]:
        """(the target names as a list, their variables)."""
        names = [targets] if isinstance(targets, str) else list(targets)
        index = self.net.index
        try:
            return names, tuple(index[t] for t in names)
        except (KeyError, TypeError):
            for t in names:
                self.values.check_node(t)
            raise  # pragma: no cover - check_node raised

    def _parse(self, evidence: Mapping | None, soft: SoftEvidence | None, rule: str) -> tuple[dict, dict]:
        """One query's evidence: (variable → code, an int; variable → q, shape (1, k)), sorted keys."""
        hard = {}
        if evidence:
            index, value = self.net.index, self.values.value
            for node, val in evidence.items():
                hard[index[node]] = value(node, val)
            if len(hard) > 1:
                hard = dict(sorted(hard.items()))
        qs = {}
        if soft:
            check_soft_rule(rule)
            for node, dist in soft.items():
                q = self.values.soft_vector(node, dist)
                if evidence and node in evidence:
                    raise EvidenceError(f"{node} is given twice: as hard evidence and as soft evidence")
                qs[self.net.index[node]] = q[None, :]
            qs = dict(sorted(qs.items()))
        return hard, qs

    def query(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, np.ndarray]:
        """Posterior marginal of each target, target → array, shape (n_values,), in the node's value order.

        ``evidence``: node → value (a name, an alias such as ``circle``, or an index); ``soft``: node →
        {value: probability} or a vector over its values; ``soft_rule``: ``"virtual"`` (likelihood evidence,
        the originals' choice) or ``"jeffrey"``. Raises UnknownNodeError, UnknownValueError, EvidenceError,
        ImpossibleEvidenceError (all ValueError).
        """
        names, tv = self._variables(targets)
        hard, qs = self._parse(evidence, soft, soft_rule)
        out, possible, hard_possible = self._answer(tv, hard, qs, soft_rule, 1)
        if not possible[0]:
            raise self.values.impossible(evidence, soft, bool(hard_possible[0]))
        return {t: out[v][0].copy() for t, v in zip(names, tv, strict=True)}

    def word_probability_array(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> np.ndarray:
        """P(word = present | evidence) for every binary leaf, shape (n_words,), ``binary_leaves`` order."""
        if not self.binary_leaves:
            return np.zeros(0)
        res = self.query(self.binary_leaves, evidence, soft, soft_rule)
        return np.array([res[w][1] for w in self.binary_leaves])

    def probability_of_evidence(self, evidence: Mapping[str, str | int] | None = None) -> float:
        """P(hard evidence) under the model (0 for impossible evidence; with all-zero rows, the probability
        that the evidence holds and no excluded configuration occurs)."""
        hard, _ = self._parse(evidence, None, "virtual")
        return float(np.exp(self.backend.log_mass(hard, 1)[0]))

    # ------------------------------------------------------------------ batches
    def query_batch(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, Sequence] | None = None,
        soft: Mapping[str, np.ndarray] | None = None,
        soft_rule: SoftRule = "virtual",
        errors: Literal["raise", "nan"] = "raise",
    ) -> dict[str, np.ndarray]:
        """Posterior marginals for many evidence sets at once: target → array, shape (n, n_values).

        ``evidence``: node → n values (names or indices; None, NaN or -1 = not observed), e.g. the columns
        of a DataFrame; ``soft``: node → array, shape (n, n_values); ``errors``: ``"raise"`` an
        ImpossibleEvidenceError naming the first impossible row, or give that row ``nan``.

        Rows are grouped by which nodes they observe (a row without a value for a node does not observe
        it); within a group, rows with the same hard evidence and no soft evidence are answered once.
        """
        names, tv = self._variables(targets)
        evidence = dict(evidence or {})
        soft = dict(soft or {})
        n = batch_length(evidence, soft)
        check_soft_rule(soft_rule)
        codes = {node: self.values.codes(node, vals, n) for node, vals in evidence.items()}
        checked = {node: self.values.batch_soft(node, arr, n, evidence) for node, arr in soft.items()}
        qs = dict(sorted((self.net.index[node], q) for node, q in checked.items()))
        hard = dict(sorted((self.net.index[node], c) for node, c in codes.items()))
        groups = self._groups(hard, n)
        if len(groups) == 1 and groups[0][0] is None:  # every row observes the same nodes
            out, possible, hard_possible = self._unique_rows(tv, hard, qs, soft_rule, n)
            out = {  # the caller's own arrays: never a cached or broadcast one
                v: np.array(m) if n == 1 or not (m.flags.writeable and m.base is None) else m
                for v, m in out.items()
            }
            groups = []
        else:
            out = {v: np.full((n, self.net.cards[v]), np.nan) for v in tv}
            possible = np.ones(n, dtype=bool)
            hard_possible = np.zeros(n, dtype=bool)
        for rows, group in groups:  # each pattern of observed nodes in its rows (never None here)
            sub = {v: hard[v][rows] for v in group}
            res, ok, hp = self._unique_rows(
                tv, sub, {v: q[rows] for v, q in qs.items()}, soft_rule, len(rows)
            )
            for v in set(tv):
                out[v][rows] = res[v]
            possible[rows], hard_possible[rows] = ok, hp
        if errors == "raise" and not possible.all():
            k = int(np.flatnonzero(~possible)[0])
            raise self.values.impossible_row(
                k, codes, list(soft), int((~possible).sum()), bool(hard_possible[k])
            )
        return {t: out[v] for t, v in zip(names, tv, strict=True)}

    @staticmethod
    def _groups(hard: dict[int, Array], n: int) -> list[tuple[Array | None, tuple[int, ...]]]:
        """(rows or None for all, observed variables): the rows of each pattern of observed nodes."""
        seen = {v: c >= 0 for v, c in hard.items()}
        partial = [v for v, s in seen.items() if not s.all()]
        if not partial:
            return [(None, tuple(hard))]
        if len(partial) < 63:
            key = np.zeros(n, dtype=np.int64)
            for i, v in enumerate(partial):
                key |= seen[v].astype(np.int64) << i
            patterns, inverse = np.unique(key, return_inverse=True)
            bits = [[bool(p >> i & 1) for i in range(len(partial))] for p in patterns.tolist()]
        else:  # pragma: no cover - 63 or more partly observed columns
            patterns, inverse = np.unique(
                np.stack([seen[v] for v in partial], axis=1), axis=0, return_inverse=True
            )
            bits = patterns.tolist()
        inverse = inverse.ravel()
        always = [v for v in hard if v not in partial]
        groups = [tuple(sorted(always + [v for v, b in zip(partial, on, strict=True) if b])) for on in bits]
        return [(np.flatnonzero(inverse == k), group) for k, group in enumerate(groups)]

    def _unique_rows(
        self, targets: tuple[int, ...], hard: dict[int, Array], soft: dict[int, Array], rule: str, rows: int
    ) -> tuple[dict[int, Array], Array, Array]:
        """:meth:`_answer`, with rows of the same hard evidence (and no soft evidence) answered once: their
        key is the mixed-radix number of their values, a one-dimensional integer."""
        if self.deduplicate and hard and not soft and rows > 1:
            cards = [self.net.cards[v] for v in hard]
            space = math.prod(cards)
            if space < 1 << 62:
                key = np.zeros(rows, dtype=np.int64)
                for v, k in zip(hard, cards, strict=True):
                    key *= k
                    key += hard[v]
                if space <= max(1 << 16, 4 * rows):  # a table over every key: no sort
                    seen = np.zeros(space, dtype=bool)
                    seen[key] = True
                    uniq = np.flatnonzero(seen)
                    lookup = np.empty(space, dtype=np.intp)
                    lookup[uniq] = np.arange(len(uniq))
                    inverse = lookup[key]
                else:
                    uniq, inverse = np.unique(key, return_inverse=True)
                codes = dict(zip(hard, np.unravel_index(uniq, cards), strict=True))
            else:  # pragma: no cover - more joint values than an int64 holds
                _, first, inverse = np.unique(
                    np.stack(list(hard.values()), axis=1), axis=0, return_index=True, return_inverse=True
                )
                codes = {v: c[first] for v, c in hard.items()}
            n = len(next(iter(codes.values())))
            if n < rows:
                inverse = inverse.ravel()
                res, ok, hp = self._answer(targets, codes, {}, rule, n)
                return (
                    {v: np.take(m, inverse, axis=0) for v, m in res.items()},
                    np.take(ok, inverse),
                    np.take(hp, inverse),
                )
        return self._answer(targets, hard, soft, rule, rows)

    # ------------------------------------------------------------------ labelled results (pandas)
    def posterior(
        self,
        target: str,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> pd.Series:
        """``p(target | evidence)``: a Series indexed by the target's values, named after the target (the
        labelled form of :meth:`query`: same arguments, same errors).

        >>> from glu.bn import learn_bn
        >>> from glu.data import load_experiments
        >>> eng = make_engine(learn_bn(load_experiments("synthetic")))
        >>> eng.posterior("ObjVel", {"Action": "tap", "Shape": "sphere", "Size": "small"}).round(3)
        ObjVel
        slow      0.015
        medium    0.121
        fast      0.863
        Name: ObjVel, dtype: float64
        """
        return series(
            self.query(target, evidence, soft, soft_rule)[target], self.labels.index(target), target
        )

    def posteriors(
        self,
        targets: Sequence[str],
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, pd.Series]:
        """:meth:`posterior` of several targets from one computation: target → Series."""
        res = self.query(list(targets), evidence, soft, soft_rule)
        return {t: series(p, self.labels.index(t), t) for t, p in res.items()}

    def marginals(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, pd.Series]:
        """The posterior of every node: node → Series indexed by its values.

        >>> from glu.bn import learn_bn
        >>> from glu.data import load_experiments
        >>> eng = make_engine(learn_bn(load_experiments("synthetic")))
        >>> m = eng.marginals({"Action": "tap"})
        >>> len(m), m["Action"].to_dict()
        (57, {'grasp': 0.0, 'tap': 1.0, 'touch': 0.0})
        """
        return self.posteriors(self.nodes, evidence, soft, soft_rule)

    def word_probabilities(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> pd.Series:
        """P(word = present | evidence) for every word node: a Series indexed by word (the labelled form
        of :meth:`word_probability_array`).

        >>> from glu.bn import learn_bn
        >>> from glu.data import load_experiments
        >>> eng = make_engine(learn_bn(load_experiments("synthetic")))
        >>> eng.word_probabilities({"Action": "tap"})[["tapping", "grasping"]].round(3).to_dict()
        {'tapping': 0.192, 'grasping': 0.0}
        """
        probs = self.word_probability_array(evidence, soft, soft_rule)
        return series(probs, self.labels.named("\0words", self.binary_leaves, "word"), "p(present)")

    def posterior_table(
        self,
        target: str,
        evidence: pd.DataFrame,
        soft: Mapping[str, np.ndarray] | None = None,
        soft_rule: SoftRule = "virtual",
        errors: str = "raise",
    ) -> pd.DataFrame:
        """``p(target | row)`` for every row of ``evidence``: a DataFrame, one column per value.

        ``evidence`` has one column per observed node (value names; NaN or None = not observed in that
        row), n rows; ``soft``: node → array, shape (n, n_values); the result, n rows × n_values of
        ``target``, keeps its index.

        >>> import pandas as pd
        >>> from glu.bn import learn_bn
        >>> from glu.data import load_experiments
        >>> eng = make_engine(learn_bn(load_experiments("synthetic")))
        >>> rows = pd.DataFrame({"Action": ["tap", "tap"], "Shape": ["sphere", "box"]}, index=["ball", "box"])
        >>> eng.posterior_table("ObjVel", rows).round(2)
        ObjVel  slow  medium  fast
        ball    0.06    0.30  0.65
        box     0.57    0.36  0.07
        """
        import pandas as pd

        cols = {c: evidence[c].tolist() for c in evidence.columns}
        res = self.query_batch([target], cols, soft, soft_rule, errors=errors)[target]  # type: ignore[arg-type]
        return pd.DataFrame(res, index=evidence.index, columns=self.labels.index(target))
