"""Exact inference in any discrete Bayesian network: one interface, two engines.

``InferenceEngine(bn)`` answers queries about a :class:`~glu.bn.model.BayesNet` — GLU's Affordance–Words
network, a network learned from a lab's own schema, or one imported from BIF, XMLBIF or UAI — and picks
the engine that suits its shape:

:class:`~glu.bn.core.CoreEngine`
    for networks shaped like GLU's: a small *core* (the affordance nodes and every node with children)
    whose joint table fits in memory, and *leaves* (the words) hanging off it. It multiplies the core into
    one table once and answers a query by slicing it: microseconds a query.
:class:`~glu.bn.junction.JunctionTreeEngine`
    for any other network: exact inference on a junction tree planned from the structure
    (:mod:`glu.bn.plan`), with messages vectorised over a batch of evidence sets. The size of its largest
    table is known before it is built; past a limit (``max_table``, ``$GLU_MAX_TABLE``) the engine is
    refused in one line with that size and the elimination width.

``method="auto"`` (the default) takes the core engine when its tables are small (:data:`CORE_MAX_STATES`,
:data:`CORE_MAX_ENTRIES`), else the junction tree; ``method="core"`` or ``"junction"`` forces one. Both
give the same posteriors (the tests compare them with each other, with pgmpy and with pyAgrum).

Evidence, for every engine:

* hard evidence on any node: ``{"Action": "tap", "rolls": "present"}`` (value names, aliases or indices);
* soft evidence on any node, a distribution ``q`` over its values, entered either as *virtual*
  (likelihood) evidence, ``p(X | e) ∝ Σ_a p(X, a | e) q(a)`` — the originals' soft fusion — or by
  *Jeffrey's rule*, which makes the node's posterior marginal equal to ``q``:
  ``p(X | e) = Σ_a p(X | e, A=a) q(a)`` (several Jeffrey nodes: iterative proportional fitting);
* evidence of probability 0 raises :class:`~glu.errors.ImpossibleEvidenceError` naming it;
* many evidence sets at once: :meth:`InferenceEngine.query_batch` (arrays) and
  :meth:`InferenceEngine.posterior_table` (a DataFrame).

Results come in two forms: the numeric ones (:meth:`~InferenceEngine.query`,
:meth:`~InferenceEngine.query_batch`, :meth:`~InferenceEngine.word_probability_array`: NumPy arrays in the
nodes' value order, the fast path of every experiment) and the labelled ones
(:meth:`~InferenceEngine.posterior`, :meth:`~InferenceEngine.posteriors`,
:meth:`~InferenceEngine.marginals`, :meth:`~InferenceEngine.posterior_table`,
:meth:`~InferenceEngine.word_probabilities`: pandas objects indexed by value and word names).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from glu.bn.model import BayesNet
from glu.bn.soft import SUM_TOL, SoftRule
from glu.errors import EvidenceError, ImpossibleEvidenceError, ModelError, UnknownNodeError
from glu.schema import unknown_node_message

if TYPE_CHECKING:
    import pandas as pd

SoftEvidence = Mapping[str, Mapping[str, float] | Sequence[float] | np.ndarray]
Method = Literal["auto", "core", "junction"]
METHODS: tuple[str, ...] = ("auto", "core", "junction")
ENGINES: dict[str, type] = {}
"""The engine of each method, as the subclasses register themselves (``class CoreEngine(…, method="core")``);
:mod:`glu.bn` imports both, so they are registered before any engine is made."""
CORE_MAX_STATES = 1 << 16
"""``method="auto"`` takes the core engine only if the core's joint table has at most this many states …"""
CORE_MAX_ENTRIES = 1 << 22
"""… and its leaf tables over the core (states × (leaf values + 2)) at most this many entries."""
IPFP_TOL, IPFP_MAX_ITER = 1e-13, 10_000


def core_split(bn: BayesNet) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(core, leaves): the affordance nodes and every node with children, then the other nodes."""
    has_children = {p for n in bn.nodes for p in bn.parents[n]}
    core = tuple(n for n in bn.nodes if n in bn.schema.affordance_nodes or n in has_children)
    return core, tuple(n for n in bn.nodes if n not in core)


def core_size(bn: BayesNet) -> tuple[int, int]:
    """(states of the core joint, entries of the core engine's tables) — Python ints, never overflowing."""
    core, leaves = core_split(bn)
    states = math.prod(bn.schema.cardinality(n) for n in core)
    return states, states * (2 + sum(bn.schema.cardinality(n) for n in leaves))


def choose_method(bn: BayesNet, method: str = "auto") -> str:
    """``"core"`` or ``"junction"``: the engine ``method`` asks for, or the one that suits ``bn`` (auto)."""
    if method not in METHODS:
        raise ModelError(f"unknown inference method {method!r}; allowed: {', '.join(METHODS)}")
    if method != "auto":
        return method
    states, entries = core_size(bn)
    small = states <= CORE_MAX_STATES and entries <= CORE_MAX_ENTRIES and len(core_split(bn)[0]) <= 60
    return "core" if small else "junction"


class InferenceEngine:
    """Exact posterior marginals of a :class:`BayesNet` of any shape.

    ``InferenceEngine(bn)`` returns an instance of the chosen subclass (:class:`~glu.bn.core.CoreEngine` or
    :class:`~glu.bn.junction.JunctionTreeEngine`); both are ``InferenceEngine`` instances with this
    interface.

    Parameters
    ----------
    bn : the network
    method : ``"auto"`` (default: the core engine for GLU-shaped networks, else the junction tree),
        ``"core"`` or ``"junction"``
    max_table : the largest table the junction tree may build (entries); None: ``$GLU_MAX_TABLE`` or
        :data:`glu.bn.plan.MAX_TABLE_DEFAULT`

    Raises
    ------
    ModelError
        a junction tree past the size limit (one line: the largest table and the elimination width), or a
        core engine forced on a network whose core does not fit

    Examples
    --------
    On glu's synthetic data (the real data gives the GLU 2017 bars):

    >>> from glu.bn import learn_bn
    >>> from glu.data import load_experiments
    >>> eng = InferenceEngine(learn_bn(load_experiments("synthetic")))
    >>> p = eng.query(["ObjVel"], {"Action": "tap", "Shape": "sphere", "Size": "small"})["ObjVel"]
    >>> p.round(3)                                                      # slow, medium, fast
    array([0.015, 0.121, 0.863])
    >>> type(eng).__name__, isinstance(eng, InferenceEngine)
    ('CoreEngine', True)
    """

    bn: BayesNet
    nodes: tuple[str, ...]
    method: str
    binary_leaves: tuple[str, ...]
    _value_index: dict[str, dict[str, int]]

    def __new__(
        cls, bn: BayesNet | None = None, method: Method = "auto", max_table: int | None = None
    ) -> Any:
        if cls is InferenceEngine and bn is not None:  # (unpickling calls __new__ without arguments)
            kind = choose_method(bn, method)
            if kind not in ENGINES:  # pragma: no cover - glu.bn imports both engines
                raise ModelError(f"no {kind} engine is loaded (import glu.bn, which loads them)")
            cls = ENGINES[kind]
        return super().__new__(cls)

    def __init_subclass__(cls, method: str = "", **kwargs: Any) -> None:
        """A subclass given ``method=`` is the engine :meth:`__new__` returns for that method."""
        super().__init_subclass__(**kwargs)
        if method:
            ENGINES[method] = cls

    def _setup(self, bn: BayesNet, method: str) -> None:
        """What every engine shares: the network, its nodes, value look-up (aliases included), word nodes."""
        self.bn = bn
        self.nodes = bn.nodes
        self.method = method
        self._value_index = {}
        for n in bn.nodes:
            vals = bn.schema.values_of(n)
            d = {v: i for i, v in enumerate(vals)}
            for alias, v in bn.schema.aliases.get(n, {}).items():
                if v in d:  # an alias of a value this model does not have does not apply
                    d[alias] = d[v]
            self._value_index[n] = d
        _, leaves = core_split(bn)
        self.binary_leaves = tuple(w for w in leaves if bn.schema.cardinality(w) == 2)

    # ------------------------------------------------------------------ parsing evidence
    def _value(self, node: str, value: str | int) -> int:
        idx = self._value_index.get(node)
        if idx is None:
            raise UnknownNodeError(unknown_node_message(node, self.nodes))
        if isinstance(value, int | np.integer) and not isinstance(value, bool):
            if 0 <= value < len(self.bn.schema.values_of(node)):
                return int(value)
        else:
            i = idx.get(value)
            if i is not None:
                return i
        return self.bn.schema.value_index(node, str(value))  # raises UnknownValueError

    def _check_node(self, node: str) -> None:
        if node not in self._value_index:
            raise UnknownNodeError(unknown_node_message(node, self.nodes))

    def _codes(self, node: str, values: Sequence, n: int) -> np.ndarray:
        """A batch column as value indices, shape (n,): -1 where not observed (None, NaN, a negative
        index)."""
        self._check_node(node)
        if isinstance(values, np.ndarray) and values.dtype.kind in "iu" and values.ndim == 1:
            if len(values) != n:
                raise EvidenceError(f"batch evidence on {node} has {len(values)} rows, expected {n}")
            out = np.where(values < 0, -1, values).astype(np.intp)
            bad = out >= self.bn.schema.cardinality(node)
            if bad.any():
                self._value(node, int(out[bad][0]))  # raises UnknownValueError, naming the value
            return out
        vals = list(values)
        if len(vals) != n:
            raise EvidenceError(f"batch evidence on {node} has {len(vals)} rows, expected {n}")
        out = np.empty(n, dtype=np.intp)
        for i, v in enumerate(vals):
            if (
                v is None
                or (isinstance(v, float) and np.isnan(v))
                or (isinstance(v, int | np.integer) and v < 0)
            ):
                out[i] = -1
            else:
                out[i] = self._value(node, v)
        return out

    def _targets(self, targets: Sequence[str] | str) -> list[str]:
        """The target nodes as a list, each checked to be a node of the network."""
        targets = [targets] if isinstance(targets, str) else list(targets)
        for t in targets:
            self._check_node(t)
        return targets

    def _batch_soft(self, node: str, arr: np.ndarray, n: int, evidence: Mapping[str, Sequence]) -> np.ndarray:
        """Batch soft evidence on ``node`` checked (shape (n, n_values), every row a distribution, the node
        not also in the hard ``evidence``) and normalised to sum 1 per row."""
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
        return arr / sums[:, None]

    def soft_vector(self, node: str, dist: Mapping[str, float] | Sequence[float] | np.ndarray) -> np.ndarray:
        """Validate soft evidence on ``node`` and return it as a vector over the node's values, shape (k,)."""
        self._check_node(node)
        values = self.bn.schema.values_of(node)
        if isinstance(dist, Mapping):
            q = np.zeros(len(values))
            for k, p in dist.items():
                if isinstance(p, bool) or not isinstance(p, int | float | np.integer | np.floating):
                    raise EvidenceError(
                        f"soft evidence on {node}: the probability of {k!r} must be a number, got {p!r}"
                    )
                q[self._value(node, k)] = p
        else:
            try:
                q = np.asarray(dist, dtype=float)
            except (TypeError, ValueError):
                raise EvidenceError(
                    f"soft evidence on {node} must be a list of {len(values)} numbers ({', '.join(values)}) "
                    f"or {{value: probability}}, got {dist!r}"
                ) from None
            if q.ndim != 1:
                raise EvidenceError(
                    f"soft evidence on {node} must be a flat list of {len(values)} numbers "
                    f"({', '.join(values)})"
                )
            if q.shape != (len(values),):
                raise EvidenceError(
                    f"soft evidence on {node} has {q.size} entries; expected {len(values)} "
                    f"({', '.join(values)})"
                )
        # an entry above 1 is refused before the sum, which could overflow (1e308 + 1e308)
        if (
            not np.all(np.isfinite(q))
            or (q < 0).any()
            or (q > 1.0 + SUM_TOL).any()
            or abs(q.sum() - 1.0) > SUM_TOL
        ):
            shown = ", ".join(f"{v}:{p:g}" for v, p in zip(values, q, strict=True))
            raise EvidenceError(
                f"soft evidence on {node} is not a distribution over its values ({shown}): "
                "entries must be non-negative and sum to 1"
            )
        return q / q.sum()

    def _describe(self, evidence: Mapping | None, soft: Mapping | None) -> str:
        parts = [f"{k}={v}" for k, v in (evidence or {}).items()] + [f"soft({k})" for k in (soft or {})]
        return ", ".join(parts) if parts else "no evidence"

    def _impossible(
        self, evidence: Mapping | None, soft: Mapping | None, hard_possible: bool = False
    ) -> ImpossibleEvidenceError:
        hint = ""
        zr = self.bn.zero_rows()
        if hard_possible:
            hint = (
                " (the hard evidence alone is possible: the soft evidence gives probability 0 to every "
                "value it allows)"
            )
        elif zr:
            hint = (
                f" (the model has all-zero CPT rows for {', '.join(zr)}, which exclude some affordance "
                "configurations; learn with unseen_words='uniform' to keep them)"
            )
        return ImpossibleEvidenceError(
            f"impossible evidence: {self._describe(evidence, soft)} has probability 0 under the model{hint}"
        )

    def _impossible_row(
        self,
        i: int,
        codes: Mapping[str, np.ndarray],
        soft: Sequence[str],
        n_bad: int,
        hard_possible: bool = False,
    ) -> ImpossibleEvidenceError:
        """The error for row ``i`` of a batch (node → value codes, -1 = not observed; the soft nodes), the
        first of ``n_bad`` impossible rows."""
        ev = {node: self.bn.schema.values_of(node)[c[i]] for node, c in codes.items() if c[i] >= 0}
        return ImpossibleEvidenceError(
            f"row {i}: {self._impossible(ev, dict.fromkeys(soft), hard_possible)}"
            + (f" ({n_bad} impossible rows in all)" if n_bad > 1 else "")
        )

    # ------------------------------------------------------------------ numeric results (each engine)
    def query(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, np.ndarray]:
        """Posterior marginal of each target node given hard and soft evidence (the numeric form).

        Parameters
        ----------
        targets : node names
        evidence : hard evidence, node → value (a value name, an alias such as ``circle``, or an index)
        soft : soft evidence, node → {value: probability} or a vector over its values
        soft_rule : ``"virtual"`` (likelihood evidence, the originals' choice) or ``"jeffrey"``

        Returns
        -------
        dict target → array, shape (n_values,), the posterior in the node's value order
        (:meth:`posteriors` gives the same as labelled Series).

        Raises
        ------
        UnknownNodeError, UnknownValueError, EvidenceError, ImpossibleEvidenceError (all ValueError)
        """
        raise NotImplementedError  # pragma: no cover - each engine defines it

    def query_batch(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, Sequence] | None = None,
        soft: Mapping[str, np.ndarray] | None = None,
        soft_rule: SoftRule = "virtual",
        errors: Literal["raise", "nan"] = "raise",
    ) -> dict[str, np.ndarray]:
        """Posterior marginals for many evidence sets at once, vectorised over the rows.

        Parameters
        ----------
        targets : node names
        evidence : node → sequence of n values (names or indices; None, NaN or -1 = not observed), e.g. the
            columns of a DataFrame
        soft : node → array, shape (n, n_values): one soft-evidence distribution per row
        soft_rule : ``"virtual"`` or ``"jeffrey"``
        errors : ``"raise"`` an :class:`ImpossibleEvidenceError` naming the first impossible row, or give
            that row ``nan``

        Returns
        -------
        dict target → array, shape (n, n_values).
        """
        raise NotImplementedError  # pragma: no cover - each engine defines it

    def word_probability_array(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> np.ndarray:
        """P(word = present | evidence) for every binary leaf, shape (n_words,), in ``binary_leaves``
        order."""
        if not self.binary_leaves:
            return np.zeros(0)
        res = self.query(list(self.binary_leaves), evidence, soft, soft_rule)
        return np.array([res[w][1] for w in self.binary_leaves])

    def probability_of_evidence(self, evidence: Mapping[str, str | int] | None = None) -> float:
        """P(hard evidence) under the model (0 for impossible evidence)."""
        raise NotImplementedError  # pragma: no cover - each engine defines it

    # ------------------------------------------------------------------ labelled results (pandas)
    def posterior(
        self,
        target: str,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> pd.Series:
        """``p(target | evidence)`` as a Series indexed by the target's values, named after the target.

        The labelled form of :meth:`query` (same arguments, same errors).

        >>> from glu.bn import learn_bn
        >>> from glu.data import load_experiments
        >>> eng = InferenceEngine(learn_bn(load_experiments("synthetic")))
        >>> eng.posterior("ObjVel", {"Action": "tap", "Shape": "sphere", "Size": "small"}).round(3)
        ObjVel
        slow      0.015
        medium    0.121
        fast      0.863
        Name: ObjVel, dtype: float64
        """
        return self.posteriors([target], evidence, soft, soft_rule)[target]

    def posteriors(
        self,
        targets: Sequence[str],
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, pd.Series]:
        """:meth:`posterior` of several targets from one computation: target → Series."""
        import pandas as pd

        res = self.query(list(targets), evidence, soft, soft_rule)
        return {
            t: pd.Series(p, index=pd.Index(self.bn.schema.values_of(t), name=t), name=t)
            for t, p in res.items()
        }

    def marginals(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, pd.Series]:
        """The posterior of every node: node → Series indexed by its values (:meth:`posteriors` of all nodes).

        >>> from glu.bn import learn_bn
        >>> from glu.data import load_experiments
        >>> eng = InferenceEngine(learn_bn(load_experiments("synthetic")))
        >>> m = eng.marginals({"Action": "tap"})
        >>> len(m), m["Action"].to_dict()
        (57, {'grasp': 0.0, 'tap': 1.0, 'touch': 0.0})
        """
        return self.posteriors(list(self.nodes), evidence, soft, soft_rule)

    def word_probabilities(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> pd.Series:
        """P(word = present | evidence) for every word node, a Series indexed by word (``binary_leaves``).

        The labelled form of :meth:`word_probability_array`.

        >>> from glu.bn import learn_bn
        >>> from glu.data import load_experiments
        >>> eng = InferenceEngine(learn_bn(load_experiments("synthetic")))
        >>> eng.word_probabilities({"Action": "tap"})[["tapping", "grasping"]].round(3).to_dict()
        {'tapping': 0.192, 'grasping': 0.0}
        """
        import pandas as pd

        probs = self.word_probability_array(evidence, soft, soft_rule)
        return pd.Series(probs, index=pd.Index(self.binary_leaves, name="word"), name="p(present)")

    def posterior_table(
        self,
        target: str,
        evidence: pd.DataFrame,
        soft: Mapping[str, np.ndarray] | None = None,
        soft_rule: SoftRule = "virtual",
        errors: str = "raise",
    ) -> pd.DataFrame:
        """``p(target | row)`` for every row of ``evidence`` at once: a DataFrame, one column per value.

        ``evidence`` has one column per observed node (value names; NaN or None = not observed in that row);
        the result keeps its index. ``soft`` and ``errors`` are as in :meth:`query_batch`.

        >>> import pandas as pd
        >>> from glu.bn import learn_bn
        >>> from glu.data import load_experiments
        >>> eng = InferenceEngine(learn_bn(load_experiments("synthetic")))
        >>> rows = pd.DataFrame({"Action": ["tap", "tap"], "Shape": ["sphere", "box"]}, index=["ball", "box"])
        >>> eng.posterior_table("ObjVel", rows).round(2)
        ObjVel  slow  medium  fast
        ball    0.06    0.30  0.65
        box     0.57    0.36  0.07
        """
        import pandas as pd

        cols = {c: evidence[c].tolist() for c in evidence.columns}
        res = self.query_batch([target], cols, soft, soft_rule, errors=errors)[target]  # type: ignore[arg-type]
        return pd.DataFrame(
            res, index=evidence.index, columns=pd.Index(self.bn.schema.values_of(target), name=target)
        )
