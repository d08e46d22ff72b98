"""The core-and-leaves engine's arithmetic: exact inference in networks shaped like GLU's, over rows.

The Affordance–Words network has a small *core* (the 8 affordance nodes: 3·4·2·3·3·3·2·2 = 2592 joint
states) and many *leaves* (the 49 words), each hanging off core nodes only. :class:`CoreBackend` therefore

1. multiplies the core CPTs into the joint ``P(core)`` once (shape (3, 4, 2, 3, 3, 3, 2, 2));
2. folds every unobserved leaf into it through its row sums ``m_L(pa) = Σ_v P(L=v | pa)`` — 1 for a
   normal row, 0 for the all-zero rows of parent configurations a word never saw (the original's quirk:
   those core states get probability 0 in every query, as in the original BNT inference);
3. per evidence pattern (cached): sums the joint down to the core axes the pattern needs, observed axes
   first and flattened, so that a row's table is one gather; and stacks the ratio tables
   ``R_L[v] = P(L=v | pa) / m_L(pa)`` of the leaves it observes or asks for over the same axes;
4. per row of evidence: gathers that table at the observed core values, multiplies in the observed leaves'
   ratios and the likelihoods of soft evidence (on a core node: along its axis; on a leaf:
   ``Σ_v λ(v) R_L[v]``), and sums to the targets — every leaf target at once, one product.

pgmpy's VariableElimination and pyAgrum are the independent references in the tests.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from glu.bn.model import BayesNet
from glu.bn.network import code_of
from glu.errors import ModelError

MAX_CORE_STATES = 1 << 22
"""The largest core joint this engine builds when asked for explicitly (``method="core"``)."""


def core_split(bn: BayesNet) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(core, leaves): the affordance nodes and every node with children, then the other nodes."""
    keep = set(bn.schema.affordance_nodes)
    for ps in bn.parents.values():
        keep.update(ps)
    nodes = bn.nodes
    return tuple(n for n in nodes if n in keep), tuple(n for n in nodes if n not in keep)


def core_size(bn: BayesNet) -> tuple[int, int]:
    """(states of the core joint, entries of the core engine's tables) — Python ints, never overflowing."""
    core, leaves = core_split(bn)
    states = math.prod(bn.cpts[n].shape[-1] for n in core)
    return states, states * (2 + sum(bn.cpts[n].shape[-1] for n in leaves))


def _broadcast(table: np.ndarray, axes: Sequence[int], ndim: int) -> np.ndarray:
    """View ``table`` (one axis per entry of ``axes``) as broadcastable over ``ndim`` core axes."""
    order = np.argsort(axes)
    t = table.transpose(order)
    shape = [1] * ndim
    for a, s in zip(np.asarray(axes)[order], t.shape, strict=True):
        shape[a] = s
    return t.reshape(shape)


def _observed_index(plan: CorePlan, hard: Mapping[int, np.ndarray], rows: int) -> np.ndarray:
    """Each row's index into the observed axes of ``plan``'s tables (mixed radix), shape (rows,)."""
    if rows == 1:  # the index as a Python int first: a fifth of the NumPy calls
        return np.array([sum(code_of(hard[v]) * stride for v, stride in plan.observed)])
    at = np.zeros(rows, dtype=np.intp)
    for v, stride in plan.observed:
        at = at + hard[v] * stride
    return at


@dataclass(frozen=True, eq=False)
class CorePlan:
    """One evidence pattern on the core joint (:meth:`CoreBackend.plan`).

    Attributes
    ----------
    observed : observed core variables, and the stride of each in the flattened observed axes
    kept : the free core variables kept, in axis order, and their cardinalities
    joint : the joint summed to (observed…, kept…), shape (Π observed cards, Π kept cards)
    leaves : observed or soft-evidence leaf → its ratio tables, shape (Π observed, k, Π kept)
    leaf_targets : (leaf, first column, k) in ``stacked``; ``stacked``: shape (Π observed, Σ k, Π kept)
    core_targets : (variable, summed axes of the kept table with the rows first)
    soft_core : soft-evidence core variable → its shape in the kept table with the rows first
    answers : when no row brings a factor of its own (no leaf evidence, no soft evidence): the answers for
        every combination of the observed values, made on first use (marginals, possible)
    """

    observed: tuple[tuple[int, int], ...]
    kept: tuple[int, ...]
    kept_cards: tuple[int, ...]
    joint: np.ndarray
    leaves: dict[int, np.ndarray]
    leaf_targets: tuple[tuple[int, int, int], ...]
    stacked: np.ndarray | None
    core_targets: tuple[tuple[int, tuple[int, ...]], ...]
    soft_core: dict[int, tuple[int, ...]]
    answers: list = field(default_factory=list)


class CoreBackend:
    """Exact marginals of a :class:`BayesNet` whose non-core nodes are leaves with core parents.

    Attributes
    ----------
    core, leaves : node names
    axis : core node → its axis in the joint
    shape : the joint's shape, one axis per core node
    prior_joint : P(core), shape ``shape``
    base : P(core) with every unobserved leaf summed out, shape ``shape``
    leaf_axes : leaf → the core axes of its parents
    leaf_ratio : leaf → R_L, shape ``(k, *parent cardinalities)``
    """

    method = "core"

    def __init__(self, bn: BayesNet) -> None:
        self.core, self.leaves = core_split(bn)
        n_states, _ = core_size(bn)
        if n_states > MAX_CORE_STATES or len(self.core) > 60:
            raise ModelError(
                f"the core joint of this network has {n_states:,} states; the core engine handles up to "
                f"{MAX_CORE_STATES:,}: use method='junction' (the default 'auto' does)"
            )
        index = {n: i for i, n in enumerate(bn.nodes)}
        self._var = [index[n] for n in self.core]
        self.axis = {n: i for i, n in enumerate(self.core)}
        self._axis_of = {index[n]: i for i, n in enumerate(self.core)}
        self.shape = tuple(bn.schema.cardinality(n) for n in self.core)
        ndim = len(self.core)
        joint = np.ones(self.shape)
        for n in self.core:
            axes = [self.axis[p] for p in bn.parents[n]] + [self.axis[n]]
            joint = joint * _broadcast(bn.cpts[n], axes, ndim)
        self.prior_joint = joint
        base = joint.copy()
        self.leaf_axes: dict[str, tuple[int, ...]] = {}
        self.leaf_ratio: dict[str, np.ndarray] = {}
        self._leaf: dict[int, tuple[tuple[int, ...], np.ndarray]] = {}
        for leaf in self.leaves:
            cpt = bn.cpts[leaf]
            axes = tuple(self.axis[p] for p in bn.parents[leaf])
            m = cpt.sum(axis=-1)
            ratio = np.divide(cpt, m[..., None], out=np.zeros_like(cpt), where=m[..., None] > 0)
            ratio = np.moveaxis(ratio, -1, 0)  # (k, *pa)
            self.leaf_axes[leaf], self.leaf_ratio[leaf] = axes, ratio
            self._leaf[index[leaf]] = (axes, ratio)
            if not np.all(m == 1.0):
                base = base * _broadcast(m, axes, ndim)
        self.base = base
        self._plans: dict[tuple, CorePlan] = {}

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "_plans": {}}

    # ------------------------------------------------------------------ plans
    def plan(self, observed: Sequence[int], soft: Sequence[int], targets: Sequence[int]) -> CorePlan:
        """The plan of a pattern (variable indices), cached."""
        key = (tuple(observed), tuple(soft), tuple(targets))
        plan = self._plans.get(key)
        if plan is None:
            plan = self._plans[key] = self._make_plan(*key)
        return plan

    def _make_plan(self, observed: tuple, soft: tuple, targets: tuple) -> CorePlan:
        ax = self._axis_of
        obs = [ax[v] for v in observed if v in ax]
        leaves = [v for v in (*observed, *soft) if v not in ax]
        leaf_targets = [v for v in targets if v not in ax]
        keep = {ax[v] for v in (*soft, *targets) if v in ax}
        for v in (*leaves, *leaf_targets):
            keep.update(self._leaf[v][0])
        kept = tuple(a for a in range(len(self.shape)) if a in keep and a not in obs)
        order = [*obs, *kept]
        n_obs = math.prod(self.shape[a] for a in obs)
        n_kept = math.prod(self.shape[a] for a in kept)
        unused = tuple(a for a in range(len(self.shape)) if a not in order)
        joint = self.base.sum(axis=unused) if unused else self.base
        left = [a for a in range(len(self.shape)) if a in order]  # the axes of ``joint``, in order
        joint = np.ascontiguousarray(np.transpose(joint, [left.index(a) for a in order])).reshape(
            n_obs, n_kept
        )

        ndim = len(self.shape)
        pick = (slice(None), *(slice(None) if a in order else 0 for a in range(ndim)))

        def over(v: int) -> np.ndarray:
            """A leaf's ratio tables over (observed…, kept…): shape (Π observed, k, Π kept)."""
            axes, ratio = self._leaf[v]
            k = ratio.shape[0]
            t = np.broadcast_to(_broadcast(ratio, (0, *(1 + a for a in axes)), ndim + 1), (k, *self.shape))
            t = np.transpose(t[pick], [0, *(1 + left.index(a) for a in order)]).reshape(k, n_obs, n_kept)
            return np.ascontiguousarray(np.moveaxis(t, 0, 1))

        parts = [over(v) for v in leaf_targets]
        stacked = np.ascontiguousarray(np.concatenate(parts, axis=1)) if parts else None
        starts = itertools.accumulate((t.shape[1] for t in parts), initial=0)
        spans = [(v, col, t.shape[1]) for v, col, t in zip(leaf_targets, starts, parts, strict=False)]
        kcards = tuple(self.shape[a] for a in kept)
        core_targets = tuple(
            (v, tuple(1 + i for i, a in enumerate(kept) if a != ax[v])) for v in targets if v in ax
        )
        soft_core = {
            v: (-1, *(kcards[i] if a == ax[v] else 1 for i, a in enumerate(kept))) for v in soft if v in ax
        }
        return CorePlan(
            observed=tuple(
                (self._var[a], math.prod(self.shape[b] for b in obs[i + 1 :])) for i, a in enumerate(obs)
            ),
            kept=kept,
            kept_cards=kcards,
            joint=joint,
            leaves={v: over(v) for v in leaves},
            leaf_targets=tuple(spans),
            stacked=stacked,
            core_targets=core_targets,
            soft_core=soft_core,
        )

    def size(
        self, tables: Collection[int], observed: Sequence[int], soft: Sequence[int], targets: Sequence[int]
    ) -> int:
        """Entries one row of this pattern costs (to cut a batch into chunks)."""
        plan = self.plan(observed, soft, targets)
        return plan.joint.shape[1] * (1 + (0 if plan.stacked is None else plan.stacked.shape[1]))

    # ------------------------------------------------------------------ arithmetic
    def _table(
        self,
        plan: CorePlan,
        hard: Mapping[int, np.ndarray],
        likelihood: Mapping[int, np.ndarray],
        rows: int,
        skip: int = -1,
    ) -> tuple[np.ndarray, np.ndarray]:
        """(the gathered joint with every factor of the row multiplied in but leaf ``skip``'s, shape
        (rows, Π kept); the observed index of each row, shape (rows,))."""
        at = _observed_index(plan, hard, rows)
        p = plan.joint[at]
        for v, table in plan.leaves.items():
            if v == skip:
                continue
            if v in hard:
                p = p * table[at, hard[v]]
            else:
                p = p * np.einsum("rk,rkf->rf", likelihood[v], table[at])
        if plan.soft_core:
            p = p.reshape(rows, *plan.kept_cards)
            for v, shape in plan.soft_core.items():
                p = p * likelihood[v].reshape(shape)
            p = p.reshape(rows, -1)
        return p, at

    def solve(
        self,
        targets: Sequence[int],
        hard: Mapping[int, np.ndarray],
        likelihood: Mapping[int, np.ndarray],
        rows: int,
        tables: Collection[int] = (),
    ) -> tuple[dict[int, np.ndarray], np.ndarray]:
        """Marginals of ``targets`` given hard evidence (variable → codes, shape (rows,), all ≥ 0) and
        likelihoods (variable → shape (rows, k)): (target → shape (rows, k), NaN where impossible;
        possible, shape (rows,))."""
        plan = self.plan(tuple(hard), tuple(likelihood), targets)
        if plan.leaves or plan.soft_core:
            return self._compute(plan, hard, likelihood, rows)
        # the answer depends on the observed core values alone: computed once for every combination of
        # them (the same arithmetic, one row each), then gathered
        if not plan.answers:
            names = [v for v, _ in plan.observed]
            every = np.arange(plan.joint.shape[0])
            codes = np.unravel_index(every, [self.shape[self._axis_of[v]] for v in names]) if names else ()
            plan.answers.append(self._compute(plan, dict(zip(names, codes, strict=True)), {}, len(every)))
        table, possible = plan.answers[0]
        at = _observed_index(plan, hard, rows)
        if rows == 1:  # views of one row (the engine copies what it hands out)
            i = int(at[0])
            return {v: m[i : i + 1] for v, m in table.items()}, possible[i : i + 1]
        return {v: np.take(m, at, axis=0) for v, m in table.items()}, np.take(possible, at)

    def _compute(
        self,
        plan: CorePlan,
        hard: Mapping[int, np.ndarray],
        likelihood: Mapping[int, np.ndarray],
        rows: int,
    ) -> tuple[dict[int, np.ndarray], np.ndarray]:
        """:meth:`solve`'s arithmetic on ``rows`` rows of evidence."""
        p, at = self._table(plan, hard, likelihood, rows)
        # each marginal is divided by its own sum (never inverted: a total may be subnormal), so that no
        # entry can round past 1; the leaves' by the joint's total, and clipped
        out: dict[int, np.ndarray] = {}
        full = p.reshape(rows, *plan.kept_cards)
        norm = None
        for v, axes in plan.core_targets:
            m = full.sum(axis=axes) if axes else full.reshape(rows, -1)
            norm = m.sum(axis=1, keepdims=True)
            if rows == 1:
                out[v] = m / norm if norm[0, 0] > 0 else np.array(m, dtype=float)
            else:
                out[v] = np.divide(m, norm, out=np.zeros(m.shape), where=norm > 0)
        if norm is None or plan.stacked is not None:
            norm = p.sum(axis=1, keepdims=True)
        possible = norm[:, 0] > 0
        ok = bool(possible[0]) if rows == 1 else bool(possible.all())
        if plan.stacked is not None:
            if rows == 1:
                probs = (plan.stacked[at[0]] @ p[0])[None, :]
            else:
                probs = np.einsum("rf,rkf->rk", p, plan.stacked[at])
            probs /= norm if ok else np.where(norm > 0, norm, 1.0)
            np.minimum(probs, 1.0, out=probs)
            for v, col, k in plan.leaf_targets:
                out[v] = probs[:, col : col + k]
                if v in likelihood:  # a soft leaf asked for: λ times its marginal without its own evidence
                    rest, _ = self._table(plan, hard, likelihood, rows, skip=v)
                    m = np.einsum("rf,rkf->rk", rest, plan.stacked[at][:, col : col + k]) * likelihood[v]
                    with np.errstate(invalid="ignore", divide="ignore"):
                        out[v] = m / m.sum(axis=1, keepdims=True)
        if not ok:
            for m in out.values():
                m[~possible] = np.nan
        return out, possible

    def log_mass(self, hard: Mapping[int, np.ndarray], rows: int) -> np.ndarray:
        """log P(hard evidence, every all-zero row avoided), shape (rows,) (-inf: probability 0)."""
        plan = self.plan(tuple(hard), (), ())
        p, _ = self._table(plan, hard, {}, rows)
        with np.errstate(divide="ignore"):
            return np.log(p.sum(axis=1))
