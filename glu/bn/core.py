"""The core-and-leaves engine: exact inference in networks shaped like GLU's, vectorised with NumPy.

The Affordance–Words network has a small *core* (the 8 affordance nodes: 3·4·2·3·3·3·2·2 = 2592 joint
states) and many *leaves* (the 49 words), each hanging off core nodes only. The engine therefore

1. multiplies the core CPTs into the joint ``P(core)`` once (shape (3, 4, 2, 3, 3, 3, 2, 2));
2. folds every unobserved leaf into it through its row sums ``m_L(pa) = Σ_v P(L=v | pa)`` — 1 for a
   normal row, 0 for the all-zero rows of parent configurations a word never saw (the original's quirk:
   those core states get probability 0 in every query, as in the original BNT inference);
3. answers a query by slicing the joint at the hard evidence on core nodes, multiplying in the factors of
   observed leaves and of soft evidence, and summing to the targets.

Soft evidence on core nodes is applied to the joint directly; soft evidence on a leaf, and batches with
Jeffrey's rule on several nodes, are answered by a junction tree of the same network
(:class:`~glu.bn.junction.JunctionTreeEngine`, built on first use). :class:`~glu.bn.inference.InferenceEngine`
chooses this engine when the core is small (see :func:`~glu.bn.inference.choose_method`).

pgmpy's VariableElimination is the independent reference in the tests; this engine is two to three orders
of magnitude faster (``benchmarks/bench_bn.py``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from glu.bn.batch import BatchQueries
from glu.bn.inference import (
    IPFP_MAX_ITER,
    IPFP_TOL,
    InferenceEngine,
    Method,
    SoftEvidence,
    core_size,
    core_split,
)
from glu.bn.model import BayesNet
from glu.bn.soft import SoftRule, check_soft_rule
from glu.errors import EvidenceError, ModelError, UnknownNodeError
from glu.schema import unknown_node_message

MAX_CORE_STATES = 1 << 22
"""The largest core joint this engine builds when asked for explicitly (``method="core"``)."""


def _broadcast(table: np.ndarray, axes: Sequence[int], ndim: int) -> np.ndarray:
    """View ``table`` (one axis per entry of ``axes``) as broadcastable over ``ndim`` core axes."""
    order = np.argsort(axes)
    t = table.transpose(order)
    shape = [1] * ndim
    for a, s in zip(np.asarray(axes)[order], t.shape, strict=True):
        shape[a] = s
    return t.reshape(shape)


class CoreEngine(BatchQueries, InferenceEngine, method="core"):
    """Exact marginals of a :class:`BayesNet` whose non-core nodes are leaves with core parents.

    Parameters
    ----------
    bn : the network; its affordance nodes plus every node with children form the core, all other nodes
        are leaves whose parents are core nodes.
    method, max_table : as :class:`~glu.bn.inference.InferenceEngine` (``max_table`` bounds the junction
        tree built for soft evidence on leaves)

    Attributes
    ----------
    core, leaves : node names
    axis : core node → its axis in the joint
    shape : the joint's shape, one axis per core node
    prior_joint : P(core), shape ``shape``
    base : P(core) with every unobserved leaf summed out, shape ``shape``
    base_mass : ``base.sum()`` (below 1 when all-zero rows exclude configurations)
    """

    def __init__(self, bn: BayesNet, method: Method = "core", max_table: int | None = None) -> None:
        self._setup(bn, "core")
        self._max_table = max_table
        self._junction: Any = None
        schema = bn.schema
        self.core, self.leaves = core_split(bn)
        self.axis = {n: i for i, n in enumerate(self.core)}
        self.shape = tuple(schema.cardinality(n) for n in self.core)
        n_states, _ = core_size(bn)
        if n_states > MAX_CORE_STATES or len(self.core) > 60:
            raise ModelError(
                f"the core joint of this network has {n_states:,} states; the core engine handles up to "
                f"{MAX_CORE_STATES:,}: use method='junction' (the default 'auto' does)"
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
        """P(core, all unobserved leaves summed out), shape ``self.shape`` (not normalised when rows are
        zero)."""
        self.base_mass = float(base.sum())
        self.leaf_table = np.ascontiguousarray(np.array(rows)) if rows else np.zeros((0, *self.shape))
        """Stacked R_L[v] over the full core, shape ``(Σ_L r_L, *core shape)``."""
        binary = [w for w in self.leaves if bn.schema.cardinality(w) == 2]
        self.binary_leaves = tuple(binary)
        self._present_rows = np.array([self.leaf_row[w] + 1 for w in binary], dtype=np.intp)
        self._present_flat = self.leaf_table[self._present_rows].reshape(len(binary), n_states)

    # ------------------------------------------------------------------ parsing
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

    def junction(self) -> Any:
        """The junction tree engine of the same network (built on first use), for what the core cannot do."""
        if self._junction is None:
            from glu.bn.junction import JunctionTreeEngine

            self._junction = JunctionTreeEngine(self.bn, max_table=self._max_table)
        return self._junction

    def _needs_junction(self, soft: Mapping | None) -> bool:
        """Soft evidence on a leaf (the core tables have no axis for it)."""
        return bool(soft) and any(n not in self.axis and n in self._value_index for n in soft)

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
        """See :meth:`InferenceEngine.query <glu.bn.inference.InferenceEngine.query>`."""
        if isinstance(targets, str):
            targets = [targets]
        if self._needs_junction(soft):
            return self.junction().query(targets, evidence, soft, soft_rule)
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
            out[t] = np.clip(r, 0.0, 1.0)  # a sum divided by the total may round to 1.0000000000000002
        return out

    def word_probability_array(
        self,
        evidence: Mapping[str, str | int] | None = None,
        soft: SoftEvidence | None = None,
        soft_rule: SoftRule = "virtual",
    ) -> np.ndarray:
        """P(word = present | evidence) for every binary word node, shape (n_words,), in ``binary_leaves``
        order."""
        if self._needs_junction(soft):
            return self.junction().word_probability_array(evidence, soft, soft_rule)
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
        return np.clip(probs, 0.0, 1.0)

    def probability_of_evidence(self, evidence: Mapping[str, str | int] | None = None) -> float:
        """P(hard evidence) under the model (0 for impossible evidence)."""
        core, leaf = self._split_hard(evidence)
        idx = tuple(core.get(a, slice(None)) for a in range(len(self.shape)))
        p = self.base[idx]
        for node, v in leaf.items():
            p = p * self.leaf_table[self.leaf_row[node] + v][idx]
        return float(np.sum(p))
