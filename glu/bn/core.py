"""Exact inference in the Affordance–Words network, vectorised with NumPy.

The network has a small *core* (the 8 affordance nodes: 3·4·2·3·3·3·2·2 = 2592 joint states) and many
*leaves* (the 49 words), each hanging off core nodes only. The engine therefore

1. multiplies the core CPTs into the joint ``P(core)`` once (shape (3, 4, 2, 3, 3, 3, 2, 2));
2. folds every unobserved leaf into it through its row sums ``m_L(pa) = Σ_v P(L=v | pa)`` — 1 for a
   normal row, 0 for the all-zero rows of parent configurations a word never saw (the original's quirk:
   those core states get probability 0 in every query, as in the original BNT inference);
3. answers a query by slicing the joint at the hard evidence on core nodes, multiplying in the factors of
   observed leaves and of soft evidence, and summing to the targets.

Evidence types (METHOD.md §2):

* hard evidence on any node: ``{"Action": "tap", "rolls": "present"}``;
* soft evidence on core nodes, a distribution over the node's values, entered either as *virtual*
  (likelihood) evidence, ``p(X | e) ∝ Σ_A p(X, A | e) q(A)`` — the originals' soft fusion — or by
  *Jeffrey's rule*, which makes the node's posterior marginal equal to ``q``:
  ``p(X | e) = Σ_a p(X | e, A=a) q(a)`` (several Jeffrey nodes: iterative proportional fitting).

pgmpy's VariableElimination is the independent reference in the tests; this engine is two to three orders
of magnitude faster (``benchmarks/bench_bn.py``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from glu.bn.batch import BatchQueries
from glu.bn.model import BayesNet
from glu.bn.soft import SUM_TOL, SoftRule, check_soft_rule
from glu.errors import EvidenceError, ImpossibleEvidenceError, ModelError, UnknownNodeError
from glu.schema import unknown_node_message

if TYPE_CHECKING:
    import pandas as pd

SoftEvidence = Mapping[str, Mapping[str, float] | Sequence[float] | np.ndarray]
MAX_CORE_STATES = 1 << 22
IPFP_TOL, IPFP_MAX_ITER = 1e-13, 10_000


def _broadcast(table: np.ndarray, axes: Sequence[int], ndim: int) -> np.ndarray:
    """View ``table`` (one axis per entry of ``axes``) as broadcastable over ``ndim`` core axes."""
    order = np.argsort(axes)
    t = table.transpose(order)
    shape = [1] * ndim
    for a, s in zip(np.asarray(axes)[order], t.shape, strict=True):
        shape[a] = s
    return t.reshape(shape)


class InferenceEngine(BatchQueries):
    """Exact marginals of a :class:`BayesNet` whose non-core nodes are leaves with core parents.

    Parameters
    ----------
    bn : the network; its affordance nodes plus every node with children form the core, all other nodes
        must be leaves whose parents are core nodes.

    Examples
    --------
    On glu's synthetic data (the real data gives the GLU 2017 bars):

    >>> from glu.bn import learn_bn
    >>> from glu.data import load_experiments
    >>> eng = InferenceEngine(learn_bn(load_experiments("synthetic")))
    >>> p = eng.query(["ObjVel"], {"Action": "tap", "Shape": "sphere", "Size": "small"})["ObjVel"]
    >>> p.round(3)                                                      # slow, medium, fast
    array([0.015, 0.121, 0.863])
    """

    def __init__(self, bn: BayesNet) -> None:
        self.bn = bn
        schema = bn.schema
        self.nodes = bn.nodes
        has_children = {p for n in bn.nodes for p in bn.parents[n]}
        self.core = tuple(n for n in bn.nodes if n in schema.affordance_nodes or n in has_children)
        self.leaves = tuple(n for n in bn.nodes if n not in self.core)
        self.axis = {n: i for i, n in enumerate(self.core)}
        self.shape = tuple(schema.cardinality(n) for n in self.core)
        n_states = int(np.prod(self.shape))
        if n_states > MAX_CORE_STATES:
            raise ModelError(
                f"the core joint has {n_states} states; this engine handles up to {MAX_CORE_STATES}"
            )
        ndim = len(self.core)
        for leaf in self.leaves:
            bad = [p for p in bn.parents[leaf] if p not in self.axis]
            if bad:  # pragma: no cover - impossible by construction of the core
                raise ModelError(f"leaf {leaf!r} has non-core parents {bad}")
        joint = np.ones(self.shape)
        for n in self.core:
            axes = [self.axis[p] for p in bn.parents[n]] + [self.axis[n]]
            joint = joint * _broadcast(bn.cpts[n], axes, ndim)
        self.prior_joint = joint
        """P(core) before folding in the leaves, shape ``self.shape``."""
        # Leaves: ratio tables R_L[v, pa] = P(L=v | pa) / m_L(pa) (0 where m_L = 0) and masks m_L.
        base = joint.copy()
        self.leaf_axes: dict[str, tuple[int, ...]] = {}
        self.leaf_ratio: dict[str, np.ndarray] = {}
        rows = []
        self.leaf_row: dict[str, int] = {}
        for leaf in self.leaves:
            cpt = bn.cpts[leaf]
            axes = tuple(self.axis[p] for p in bn.parents[leaf])
            m = cpt.sum(axis=-1)
            ratio = np.divide(cpt, m[..., None], out=np.zeros_like(cpt), where=m[..., None] > 0)
            ratio = np.moveaxis(ratio, -1, 0)  # (r, *pa)
            self.leaf_axes[leaf] = axes
            self.leaf_ratio[leaf] = ratio
            if not np.all(m == 1.0):
                base = base * _broadcast(m, axes, ndim)
            self.leaf_row[leaf] = len(rows)
            full = (
                np.broadcast_to(
                    ratio.reshape((ratio.shape[0],) + _broadcast(ratio[0], axes, ndim).shape),
                    (ratio.shape[0], *self.shape),
                )
                if axes
                else np.broadcast_to(ratio.reshape((-1,) + (1,) * ndim), (ratio.shape[0], *self.shape))
            )
            rows.extend(full)
        self.base = base
        """P(core, all unobserved leaves summed out), shape ``self.shape`` (not normalised when rows are zero)."""
        self.base_mass = float(base.sum())
        self.leaf_table = np.ascontiguousarray(np.array(rows)) if rows else np.zeros((0, *self.shape))
        """Stacked R_L[v] over the full core, shape (Σ_L r_L, *core shape)."""
        binary = [w for w in self.leaves if bn.schema.cardinality(w) == 2]
        self.binary_leaves = tuple(binary)
        self._present_rows = np.array([self.leaf_row[w] + 1 for w in binary], dtype=np.intp)
        self._present_flat = self.leaf_table[self._present_rows].reshape(len(binary), n_states)
        self._value_index: dict[str, dict[str, int]] = {}
        for n in bn.nodes:
            vals = bn.schema.values_of(n)
            d = {v: i for i, v in enumerate(vals)}
            for alias, v in bn.schema.aliases.get(n, {}).items():
                if v in d:  # an alias of a value this model does not have does not apply
                    d[alias] = d[v]
            self._value_index[n] = d

    # ------------------------------------------------------------------ parsing
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

    def _split_hard(self, evidence: Mapping[str, str | int] | None) -> tuple[dict[int, int], dict[str, int]]:
        core: dict[int, int] = {}
        leaf: dict[str, int] = {}
        if evidence:
            for node, value in evidence.items():
                v = self._value(node, value)
                a = self.axis.get(node)
                if a is None:
                    leaf[node] = v
                else:
                    core[a] = v
        return core, leaf

    def soft_vector(self, node: str, dist: Mapping[str, float] | Sequence[float] | np.ndarray) -> np.ndarray:
        """Validate soft evidence on ``node`` and return it as a vector over the node's values."""
        if node not in self._value_index:
            raise UnknownNodeError(unknown_node_message(node, self.nodes))
        if node not in self.axis:
            raise EvidenceError(
                f"soft evidence is supported on affordance nodes ({', '.join(self.core)}); {node!r} is a word node"
            )
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
                    f"soft evidence on {node} must be a flat list of {len(values)} numbers ({', '.join(values)})"
                )
            if q.shape != (len(values),):
                raise EvidenceError(
                    f"soft evidence on {node} has {q.size} entries; expected {len(values)} ({', '.join(values)})"
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

    # ------------------------------------------------------------------ single queries
    def _posterior_core(
        self,
        evidence: Mapping[str, str | int] | None,
        soft: SoftEvidence | None,
        soft_rule: str,
    ) -> tuple[np.ndarray, tuple, list[int], dict[str, int], dict[int, int], float]:
        core, leaf = self._split_hard(evidence)
        idx = tuple(core.get(a, slice(None)) for a in range(len(self.shape)))
        free = [a for a in range(len(self.shape)) if a not in core]
        p = self.base[idx]
        for node, v in leaf.items():
            p = p * self.leaf_table[self.leaf_row[node] + v][idx]
        if soft:
            check_soft_rule(soft_rule)
            qs = {}
            for node, dist in soft.items():
                q = self.soft_vector(node, dist)
                a = self.axis[node]
                if a in core:
                    raise EvidenceError(f"{node} is given twice: as hard evidence and as soft evidence")
                qs[free.index(a)] = q
            hard_possible = bool(p.sum() > 0.0)
            p = self._apply_soft(p, qs, soft_rule, evidence, soft)
        else:
            hard_possible = False
        total = float(p.sum())
        if not total > 0.0:
            raise self._impossible(evidence, soft, hard_possible)
        return p, idx, free, leaf, core, total

    def _apply_soft(self, p: np.ndarray, qs: dict[int, np.ndarray], rule: str, evidence, soft) -> np.ndarray:
        nd = p.ndim
        if rule == "virtual":
            for k, q in qs.items():
                # a likelihood is defined up to a factor: scale it so that its largest entry among the
                # values the evidence allows is 1, so tiny but valid likelihoods (1e-320) cannot underflow
                allowed = p.sum(axis=tuple(i for i in range(nd) if i != k)) > 0
                top = float(q[allowed].max()) if allowed.any() else 0.0
                if top > 0.0:
                    q = np.where(allowed, q, 0.0) / top
                shape = [1] * nd
                shape[k] = q.size
                p = p * q.reshape(shape)
            return p
        # Jeffrey's rule; with several soft nodes, iterative proportional fitting of their marginals.
        p = np.array(p, dtype=float)
        for _ in range(IPFP_MAX_ITER if len(qs) > 1 else 1):
            worst = 0.0
            for k, q in qs.items():
                others = tuple(i for i in range(nd) if i != k)
                z = p.sum(axis=others)
                if (q > 0).any() and ((z <= 0) & (q > 0)).any():
                    raise self._impossible(evidence, soft)
                zt = z.sum()
                if len(qs) > 1:
                    worst = max(worst, float(np.abs(z / zt - q).max()))
                f = np.divide(q, z, out=np.zeros_like(q), where=z > 0)
                shape = [1] * nd
                shape[k] = q.size
                p = p * f.reshape(shape)
            if worst < IPFP_TOL:
                break
        return p

    def query(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, np.ndarray]:
        """Posterior marginal of each target node given hard and soft evidence.

        Parameters
        ----------
        targets : node names (affordance or word nodes)
        evidence : hard evidence, node → value (a value name, an alias such as ``circle``, or an index)
        soft : soft evidence on affordance nodes, node → {value: probability} or a vector over its values
        soft_rule : ``"virtual"`` (likelihood evidence, the originals' choice) or ``"jeffrey"``

        Returns
        -------
        dict target → array, shape (n_values,), the posterior in the node's value order.

        Raises
        ------
        UnknownNodeError, UnknownValueError, EvidenceError, ImpossibleEvidenceError (all ValueError)
        """
        if isinstance(targets, str):
            targets = [targets]
        p, idx, free, leaf, core, total = self._posterior_core(evidence, soft, soft_rule)
        out: dict[str, np.ndarray] = {}
        for t in targets:
            a = self.axis.get(t)
            if a is None and t not in self._value_index:
                raise UnknownNodeError(unknown_node_message(t, self.nodes))
            if a is not None:
                if a in core:
                    r = np.zeros(self.shape[a])
                    r[core[a]] = 1.0
                else:
                    k = free.index(a)
                    r = p.sum(axis=tuple(i for i in range(p.ndim) if i != k)) / total
            elif t in leaf:
                r = np.zeros(self.bn.schema.cardinality(t))
                r[leaf[t]] = 1.0
            else:
                row = self.leaf_row[t]
                n_v = self.bn.schema.cardinality(t)
                tab = self.leaf_table[row : row + n_v][(slice(None), *idx)]
                r = (tab * p).reshape(n_v, -1).sum(axis=1) / total
            out[t] = r
        return out

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

    def word_probabilities(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> np.ndarray:
        """P(word = present | evidence) for every binary word node, shape (n_words,), in ``binary_leaves`` order."""
        p, idx, _, leaf, _, total = self._posterior_core(evidence, soft, soft_rule)
        if idx and any(not isinstance(i, slice) for i in idx):
            tab = self.leaf_table[self._present_rows][(slice(None), *idx)].reshape(
                len(self._present_rows), -1
            )
        else:
            tab = self._present_flat
        probs = tab @ np.ravel(p) / total
        for w, v in leaf.items():
            if w in self.binary_leaves:
                probs[self.binary_leaves.index(w)] = float(v == 1)
        return probs

    def marginals(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> dict[str, np.ndarray]:
        """Posterior marginals of every node (see :meth:`query`)."""
        return self.query(list(self.nodes), evidence, soft, soft_rule)

    def probability_of_evidence(self, evidence: Mapping[str, str | int] | None = None) -> float:
        """P(hard evidence) under the model (0 for impossible evidence)."""
        core, leaf = self._split_hard(evidence)
        idx = tuple(core.get(a, slice(None)) for a in range(len(self.shape)))
        p = self.base[idx]
        for node, v in leaf.items():
            p = p * self.leaf_table[self.leaf_row[node] + v][idx]
        return float(np.sum(p))
