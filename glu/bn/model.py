"""The Affordance–Words Bayesian network as data: nodes, parents, CPTs; JSON and BNT ``.mat`` input/output.

CPT layout (the original's): ``cpt[i_1, …, i_m, v] = P(node = v | parent_1 = i_1, …, parent_m = i_m)``,
parents in node order, value indices in the order of :mod:`glu.schema`.

JSON model file (``glu bn learn -o MODEL.json``; :meth:`BayesNet.save` / :meth:`BayesNet.load`)::

    {
      "format": "glu-bayesnet", "version": 1,
      "n_affordance": 8,                      # the first 8 nodes are affordance nodes, the rest words
      "meta": {"data_source": "...", "words": "lab", "unseen_words": "zero", ...},
      "schema": {"name": "...", "roles": {"Tool": "action", ...}, "roots": ["Tool", ...]},
                                              # optional: a lab's own schema (GLU's is implied)
      "nodes": [
        {"name": "ObjVel", "values": ["slow", "medium", "fast"],
         "parents": ["Action", "Shape", "Size"],
         "cpt": [[[[p, p, p], ...]]]},        # nested lists, shape (*parent cardinalities, cardinality)
        ...
      ]
    }

Floats are written with Python's ``repr``, so a saved model loads back bit for bit. The ``schema`` entry
keeps what a lab's own schema file said about its nodes (the role of each, which the experimenter sets:
:func:`glu.schema.action_node` finds the action node by its role); a model over GLU's own nodes leaves it
out (GLU's roles are implied, and its model files stay as they were).
"""

from __future__ import annotations

import graphlib
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import DataError, ModelError
from glu.files import atomic_write_json, read_json
from glu.schema import AFFORDANCE_NODES, AFFORDANCE_ROLES, FILE_ALIASES, ROLES, WORD_VALUES, Schema

FORMAT = "glu-bayesnet"
VERSION = 1
ROW_TOL = 1e-9
"""A CPT row is a distribution when it sums to 1 within this (word rows may also be all zeros)."""


_MALFORMED = (KeyError, TypeError, ValueError, AttributeError, IndexError, OverflowError, RecursionError)
"""What malformed JSON raises while a model is built from it (each becomes one ModelError line)."""


def encode(df: pd.DataFrame, schema: Schema) -> dict[str, np.ndarray]:
    """Value codes of every node: node → int64 array, shape (n_rows,), indices into the node's values."""
    out = {}
    for node in schema.nodes:
        if node not in df.columns:
            raise DataError(f"the table has no column {node!r}")
        col = df[node]
        if isinstance(col.dtype, pd.CategoricalDtype) and tuple(col.cat.categories) == schema.values_of(node):
            codes = np.asarray(col.cat.codes, dtype=np.int64)
        else:
            codes = pd.Index(schema.values_of(node)).get_indexer(col.astype(object)).astype(np.int64)
        if (codes < 0).any():
            raise DataError(f"column {node!r}: missing or unknown values; allowed: {schema.values_of(node)}")
        out[node] = codes
    return out


@dataclass(frozen=True, eq=False)
class BayesNet:
    """A discrete Bayesian network over the schema's nodes.

    Attributes
    ----------
    schema : nodes and values (affordance nodes first)
    parents : node → tuple of parent names, in node order
    cpts : node → array, shape ``(*parent cardinalities, cardinality)``
    meta : free-form provenance (data source, learning options, …)
    """

    schema: Schema
    parents: Mapping[str, tuple[str, ...]]
    cpts: Mapping[str, np.ndarray]
    meta: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.validate()

    @property
    def nodes(self) -> tuple[str, ...]:
        """All node names, affordance nodes first."""
        return self.schema.nodes

    def edges(self) -> list[tuple[str, str]]:
        """All edges ``(parent, child)``, sorted by name."""
        return sorted((p, c) for c in self.nodes for p in self.parents[c])

    def children(self, node: str) -> tuple[str, ...]:
        """The children of ``node``, in node order."""
        return tuple(c for c in self.nodes if node in self.parents[c])

    def validate(self) -> None:
        """Check the model completely; :class:`ModelError` (one line) for the first problem.

        Node names and each node's values are non-empty and distinct; parents are known nodes, distinct and
        in node order; the graph is acyclic; each CPT has the shape ``(*parent cardinalities, cardinality)``,
        finite non-negative entries, and rows that sum to 1 — or are all zeros, which only word nodes may
        have (the original's parent configurations never seen, see :mod:`glu.bn.learning`).
        """
        order = {n: i for i, n in enumerate(self.nodes)}
        if not order:
            raise ModelError("a model needs at least one node")
        if set(self.parents) != set(order) or set(self.cpts) != set(order):
            raise ModelError("parents and CPTs must be given for exactly the schema's nodes")
        if not 0 <= self.schema.n_affordance <= len(order):
            raise ModelError(f"n_affordance {self.schema.n_affordance} is outside 0 … {len(order)}")
        words = set(self.schema.word_nodes)
        for node in self.nodes:
            vals = self.schema.values_of(node)
            if (
                not isinstance(node, str)
                or not node
                or not vals
                or len(set(vals)) != len(vals)
                or not all(vals)
            ):
                raise ModelError(
                    f"node {node!r}: needs a name and distinct, non-empty value names; got {list(vals)}"
                )
            ps = self.parents[node]
            for p in ps:
                if p not in order:
                    raise ModelError(f"node {node!r}: unknown parent {p!r}")
            if list(ps) != sorted(ps, key=order.__getitem__) or len(set(ps)) != len(ps):
                raise ModelError(f"node {node!r}: parents must be distinct and in node order, got {list(ps)}")
            shape = tuple(self.schema.cardinality(p) for p in ps) + (self.schema.cardinality(node),)
            cpt = self.cpts[node]
            if cpt.shape != shape:
                raise ModelError(f"node {node!r}: CPT shape {cpt.shape}, expected {shape}")
            if not np.all(np.isfinite(cpt)) or (cpt < 0).any():
                raise ModelError(f"node {node!r}: CPT entries must be finite and non-negative")
            sums = cpt.sum(axis=-1)
            zero = sums == 0 if node in words else np.zeros(sums.shape, dtype=bool)
            ok = (np.abs(sums - 1) <= ROW_TOL) | zero
            if not ok.all():
                allowed = (
                    "1 (or be all zeros)" if node in words else "1 (all-zero rows are for word nodes only)"
                )
                raise ModelError(f"node {node!r}: CPT rows must sum to {allowed}, found {sums[~ok].flat[0]}")
        try:
            graphlib.TopologicalSorter(self.parents).prepare()
        except graphlib.CycleError as e:  # e.args[1]: the cycle, each node a parent of the next
            loop = list(e.args[1])
            if len(loop) > 12:  # a long loop: its ends, so that the message stays one readable line
                loop = [*loop[:5], f"… ({len(loop) - 9:,} more) …", *loop[-4:]]
            raise ModelError(f"the graph has a cycle: {' -> '.join(loop)}") from None

    def zero_rows(self) -> dict[str, int]:
        """Nodes whose CPT has all-zero rows (parent configurations never seen), with how many."""
        zeros = {node: int((self.cpts[node].sum(axis=-1) == 0).sum()) for node in self.nodes}
        return {node: z for node, z in zeros.items() if z}

    def log_likelihood(self, data: Any, nodes: Sequence[str] | None = None) -> float:
        """Natural-log likelihood of a table of experiments (``nodes``: only these nodes' terms).

        ``data`` is a DataFrame with a column per node (value names, or categoricals) or a mapping node →
        value codes, shape (n_rows,). Rows that a zero CPT row excludes give ``-inf``.
        """
        codes = encode(data, self.schema) if isinstance(data, pd.DataFrame) else data
        total = 0.0
        for node in nodes or self.nodes:
            cpt = self.cpts[node]
            idx = tuple(np.asarray(codes[p]) for p in self.parents[node]) + (np.asarray(codes[node]),)
            with np.errstate(divide="ignore"):
                total += float(np.log(cpt[idx]).sum())
        return total

    # ------------------------------------------------------------------ input / output
    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready form of the model (see the module docstring)."""
        out: dict[str, Any] = {
            "format": FORMAT,
            "version": VERSION,
            "n_affordance": self.schema.n_affordance,
            "meta": dict(self.meta),
        }
        s = self.schema
        if s.roles and s.affordance_nodes != AFFORDANCE_NODES:  # a lab's own schema: keep its roles
            out["schema"] = {
                "name": s.name,
                "roles": dict(s.roles),
                "roots": list(s.root_nodes),
                "aliases": {k: dict(v) for k, v in s.aliases.items()},
            }
        return {
            **out,
            "nodes": [
                {
                    "name": n,
                    "values": list(self.schema.values_of(n)),
                    "parents": list(self.parents[n]),
                    "cpt": self.cpts[n].tolist(),
                }
                for n in self.nodes
            ],
        }

    def save(self, path: str | os.PathLike) -> Path:
        """Write the model as JSON (atomically)."""
        return atomic_write_json(path, self.to_dict())

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], where: str = "model") -> BayesNet:
        """Build a model from its JSON-ready form, with clear errors for malformed input."""
        if not isinstance(d, Mapping) or d.get("format") != FORMAT:
            raise ModelError(f'{where}: not a glu Bayesian network (expected "format": "{FORMAT}")')
        if d.get("version") != VERSION:
            raise ModelError(
                f"{where}: unsupported version {d.get('version')!r}; this glu reads version {VERSION}"
            )
        try:
            nodes = d["nodes"]
            for n in nodes:
                names = [n["name"], *n["values"], *n["parents"]]
                if not all(isinstance(x, str) and x for x in names):
                    raise ModelError(
                        f"{where}: node names and values must be non-empty strings: {names[:6]!r}"
                    )
            values = {str(n["name"]): tuple(str(v) for v in n["values"]) for n in nodes}
            if len(values) != len(nodes):
                raise ModelError(f"{where}: a node name appears twice")
            extra = d.get("schema", {})
            if not isinstance(extra, Mapping):
                raise ModelError(f'{where}: "schema" must be an object, not {type(extra).__name__}')
            roots = extra.get("roots")
            roles = {str(k): str(v) for k, v in extra.get("roles", {}).items()}
            n_aff = int(d["n_affordance"])
            if not roles and tuple(values)[:n_aff] == AFFORDANCE_NODES:  # GLU's nodes: GLU's roles
                roles = dict(AFFORDANCE_ROLES)
            bad = sorted(r for r in roles.values() if r not in ROLES)
            if bad:
                raise ModelError(f"{where}: unknown role(s) {bad}; roles are {', '.join(ROLES)}")
            schema = Schema(
                values=values,
                n_affordance=n_aff,
                aliases=extra.get("aliases", FILE_ALIASES),
                roots=None if roots is None else tuple(str(r) for r in roots),
                roles=roles,
                name=str(extra.get("name", "")),
            )
            parents = {str(n["name"]): tuple(str(p) for p in n["parents"]) for n in nodes}
            cpts = {str(n["name"]): np.asarray(n["cpt"], dtype=float) for n in nodes}
            meta = d.get("meta", {})
            if not isinstance(meta, Mapping):
                raise ModelError(f'{where}: "meta" must be an object, not {type(meta).__name__}')
        except ModelError:
            raise
        except _MALFORMED as e:
            raise ModelError(f"{where}: malformed model ({type(e).__name__}: {e})") from None
        try:
            return cls(schema=schema, parents=parents, cpts=cpts, meta=dict(meta))
        except ModelError as e:
            raise ModelError(f"{where}: {e}") from None

    @classmethod
    def load(cls, path: str | os.PathLike) -> BayesNet:
        """Read a model written by :meth:`save`."""
        return cls.from_dict(read_json(path, "model file", ModelError), where=str(path))

    @classmethod
    def from_bnt_mat(cls, path: str | os.PathLike, variable: str = "netobj_lab") -> BayesNet:
        """Import an original model saved by the authors' MATLAB code (BNT), e.g. ``BN_lab.mat``."""
        from glu.matfile import MatFileError, read_mat

        path = Path(path)
        if not path.is_file():
            raise ModelError(f"{path}: no such file")
        try:
            net = read_mat(path, squeeze_me=True, struct_as_record=False)[variable]
        except KeyError:
            raise ModelError(f"{path}: no variable {variable!r} in the .mat file") from None
        except MatFileError as e:
            raise ModelError(f"{e}") from None
        except Exception as e:  # scipy raises many types for a damaged file (MatReadError, IndexError, …)
            raise ModelError(f"{path}: not a readable MATLAB file ({type(e).__name__}: {e})") from None
        try:  # the BNT structure: nodeNames, AFFORDNODES, nodeValueNames, dag, bnet.CPD{j}.CPT
            names = [str(n) for n in np.atleast_1d(net.nodeNames)]
            n_aff = len(np.atleast_1d(net.AFFORDNODES))
            value_names = [net.nodeValueNames] if n_aff == 1 else net.nodeValueNames  # squeezed: 1 × 1 cell
            values: dict[str, tuple[str, ...]] = {}
            for i, name in enumerate(names):
                if i >= n_aff:
                    values[name] = WORD_VALUES
                else:
                    vals = [str(v) for v in np.atleast_1d(value_names[i])]
                    aliases = FILE_ALIASES.get(name, {})
                    values[name] = tuple(aliases.get(v, v) for v in vals)
            dag = np.asarray(net.dag)
            n_cpd = len(np.atleast_1d(net.bnet.CPD))
            if dag.shape != (len(names), len(names)) or n_cpd != len(names) or len(set(names)) != len(names):
                raise ModelError(
                    f"{path}: an inconsistent BNT network in {variable!r}: {len(names)} node names "
                    f"({len(set(names))} distinct), a {'×'.join(map(str, dag.shape))} dag, {n_cpd} CPDs; "
                    "all must agree"
                )
            if not 0 < n_aff <= len(names):
                raise ModelError(f"{path}: {n_aff} affordance nodes among {len(names)} nodes in {variable!r}")
            parents = {
                names[j]: tuple(names[i] for i in np.flatnonzero(dag[:, j])) for j in range(len(names))
            }
            cpts = {}
            for j, name in enumerate(names):
                shape = tuple(len(values[p]) for p in parents[name]) + (len(values[name]),)
                cpts[name] = np.asarray(net.bnet.CPD[j].CPT, dtype=float).reshape(shape)
        except ModelError:
            raise
        except (AttributeError, IndexError, KeyError, TypeError, ValueError) as e:
            raise ModelError(
                f"{path}: not an original BNT network in {variable!r} ({type(e).__name__}: {e})"
            ) from None
        roles = dict(AFFORDANCE_ROLES) if tuple(names[:n_aff]) == AFFORDANCE_NODES else {}
        schema = Schema(values=values, n_affordance=n_aff, aliases=FILE_ALIASES, roles=roles)
        meta = {"data_source": f"original model imported from {path.name}", "origin": str(path)}
        return cls(schema=schema, parents=parents, cpts=cpts, meta=meta)
