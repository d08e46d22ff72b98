"""Exchange with other Bayesian-network tools: BIF, XMLBIF and UAI, written and read.

Every tool reads at least one of these: pgmpy and pyAgrum all three, GeNIe/SMILE and Weka XMLBIF,
bnlearn (R) BIF, the UAI solvers UAI. :func:`export_bn` writes a :class:`~glu.bn.model.BayesNet`,
:func:`import_bn` reads one back (the tests read glu's files with pgmpy and pyAgrum, and glu reads
theirs). Probabilities are written as the shortest decimals that read back exactly, so a round trip is
exact.

* **BIF** (the Bayesian Interchange Format of the bnlearn repository): names and values must be
  identifiers (letters, digits, ``_``; not starting with a digit).
* **XMLBIF** (version 0.3): any names; ``<TABLE>`` in C order (the node itself varies fastest).
* **UAI** (``BAYES``): numbers only — no names. glu writes the nodes in its order; reading a UAI file
  names them ``var_0``, ``var_1``, … with values ``0``, ``1``, … (as pgmpy does).

**The original's all-zero rows.** The faithful model (``unseen_words="zero"``) has CPT rows of zeros for
parent configurations a word never saw; they give those configurations probability 0 in every query.
No format allows such rows (every row must sum to 1), and renormalising them would silently change every
posterior. So :func:`export_bn` refuses such a model (``zero_rows="refuse"``, the default) with that
explanation, or exports it exactly (``zero_rows="seen"``): each zero row becomes uniform and a binary
indicator node ``seen__<node>`` with the same parents is added, ``P(seen__<node> = yes | parents) = 1``
for a row the word saw and 0 for a zero row. Observing ``seen__<node> = yes`` for every indicator (glu
lists them in :func:`seen_evidence`) gives exactly glu's posteriors in any tool; :func:`import_bn` folds
the indicators back into zero rows. A model learned with ``unseen_words="uniform"`` has no zero rows and
exports as it is.

**Which nodes are words.** glu's networks put the affordance nodes first and the word nodes (leaves with
values ``absent``, ``present``) last; an imported network is ordered the same way: leaves with those two
values are word nodes, every other node comes first, in file order. A UAI file has no value names, so
there the file's order is kept and the nodes up to the last one with children
form the core.

**UAI's table order.** The format lists a table with the last variable of the scope varying fastest (the
child, in a ``BAYES`` file); glu reads and writes that. pgmpy lays a table out with the child varying
slowest, and pyAgrum with the first parent varying fastest among the parents, so their UAI files agree
with the format only for nodes with no parent (pgmpy) or at most one (pyAgrum); use XMLBIF with them.

>>> from glu.bn import learn_bn
>>> from glu.data import load_experiments
>>> bn = learn_bn(load_experiments("synthetic"), unseen_words="uniform")
>>> text = to_bif(bn)
>>> text.splitlines()[2:5]
['variable Action {', '  type discrete [ 3 ] { grasp, tap, touch };', '}']
>>> back = from_bif(text)
>>> back.edges() == bn.edges() and all((back.cpts[n] == bn.cpts[n]).all() for n in bn.nodes)
True
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

import numpy as np

from glu.bn.bif import check_declared, numbers, read_bif, table_from_flat
from glu.bn.model import BayesNet
from glu.bn.rows import normalise_rows
from glu.errors import ModelError
from glu.files import atomic_write_text, read_text
from glu.schema import FILE_ALIASES, WORD_VALUES, Schema

FORMATS: dict[str, tuple[str, ...]] = {
    "bif": (".bif",),
    "xmlbif": (".xmlbif", ".xml", ".bifxml"),
    "uai": (".uai",),
}
"""Exchange formats and their file suffixes."""
ZERO_ROW_MODES: tuple[str, ...] = ("refuse", "seen")
SEEN_PREFIX = "seen__"
"""Prefix of the node that ``zero_rows="seen"`` adds for a word's parent configurations never seen."""
SEEN_VALUES: tuple[str, str] = ("no", "yes")
IMPORT_TOL = 1e-5
"""Rows of an imported table may sum to 1 within this, or the readers' ``renormalise`` (other tools round to
6 digits); they are rescaled to sum to 1 exactly, reported in ``meta["renormalised"]``. All-zero rows are
never accepted in a file (see :data:`SEEN_PREFIX`)."""
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_BIF_KEYWORDS = frozenset({"network", "variable", "probability", "property", "type", "discrete", "table"})


def _num(x: float) -> str:
    """The shortest decimal that reads back as ``x`` exactly, never in exponent notation (pgmpy's UAI
    grammar rejects exponents)."""
    return np.format_float_positional(float(x), unique=True, trim="-")


def format_of(path: str | os.PathLike, fmt: str | None = None) -> str:
    """The exchange format of a file: ``fmt`` if given, else from its suffix (:data:`FORMATS`)."""
    if fmt is not None:
        if fmt not in FORMATS:
            raise ModelError(f"unknown format {fmt!r}; formats: {', '.join(FORMATS)}")
        return fmt
    suffix = Path(path).suffix.lower()
    for name, suffixes in FORMATS.items():
        if suffix in suffixes:
            return name
    known = ", ".join(s for ss in FORMATS.values() for s in ss)
    raise ModelError(f"{path}: cannot tell the format from the suffix {suffix!r}; known: {known}")


# ------------------------------------------------------------------ the zero rows
def with_seen_indicators(
    bn: BayesNet,
) -> tuple[list[str], dict[str, tuple[str, ...]], dict[str, np.ndarray], dict]:
    """Nodes, parents, CPTs and values with every all-zero row made explicit (see the module docstring).

    Returns (nodes, parents, cpts, values): the model's nodes followed by one ``seen__<node>`` per node with
    zero rows; those rows made uniform. Each table has shape ``(*parent cardinalities, cardinality)``; an
    indicator's, ``(*its node's parent cardinalities, 2)``.
    """
    nodes = list(bn.nodes)
    parents = {n: tuple(bn.parents[n]) for n in nodes}
    cpts = {n: np.asarray(bn.cpts[n], dtype=float) for n in nodes}
    values = {n: tuple(bn.schema.values_of(n)) for n in nodes}
    for node in list(nodes):
        sums = cpts[node].sum(axis=-1)
        if not (sums == 0).any():
            continue
        cpt = cpts[node].copy()
        cpt[sums == 0] = 1.0 / cpt.shape[-1]
        cpts[node] = cpt
        name = SEEN_PREFIX + node
        if name in values:
            raise ModelError(f"cannot add the indicator {name!r}: the model already has a node of that name")
        seen = (sums > 0).astype(float)
        nodes.append(name)
        parents[name] = parents[node]
        cpts[name] = np.stack([1.0 - seen, seen], axis=-1)
        values[name] = SEEN_VALUES
    return nodes, parents, cpts, values


def seen_evidence(bn: BayesNet) -> dict[str, str]:
    """The evidence to give another tool with a ``zero_rows="seen"`` export:
    ``{"seen__<node>": "yes", …}``."""
    return {SEEN_PREFIX + n: "yes" for n in bn.zero_rows()}


def _prepare(bn: BayesNet, zero_rows: str) -> tuple[list[str], dict, dict, dict]:
    if zero_rows not in ZERO_ROW_MODES:
        raise ModelError(f"zero_rows={zero_rows!r}; allowed: {', '.join(ZERO_ROW_MODES)}")
    zr = bn.zero_rows()
    if zr and zero_rows == "refuse":
        shown = ", ".join(f"{n} ({k})" for n, k in list(zr.items())[:6]) + (" …" if len(zr) > 6 else "")
        raise ModelError(
            f"the model has all-zero CPT rows (parent configurations a word never saw, the original's "
            f"behaviour): {shown}; BIF, XMLBIF and UAI need every row to sum to 1 and renormalising would "
            "change every posterior. Export them as observed indicator nodes (--zero-rows seen: give "
            "seen__NODE=yes as evidence in the other tool), or learn with --unseen-words uniform"
        )
    return with_seen_indicators(bn)


# ------------------------------------------------------------------ writers
def to_bif(bn: BayesNet, zero_rows: str = "refuse", name: str = "glu") -> str:
    """The model as BIF text (see the module docstring for ``zero_rows``)."""
    nodes, parents, cpts, values = _prepare(bn, zero_rows)
    unfit = [
        (ident, n)
        for n in nodes
        for ident in (n, *values[n])
        if not _IDENT.match(ident) or ident in _BIF_KEYWORDS
    ]
    if unfit:
        shown = ", ".join(
            f"{ident!r}" + ("" if ident == n else f" (a value of {n!r})") for ident, n in unfit[:6]
        ) + (f" and {len(unfit) - 6} more" if len(unfit) > 6 else "")
        raise ModelError(
            f"BIF cannot carry {shown}: BIF names and values are ASCII identifiers (letters A–Z, digits, _; "
            "not starting with a digit; not a BIF keyword), as bnlearn and pyAgrum read them. Write XMLBIF "
            "instead (-o FILE.xmlbif: any name, read by pgmpy, pyAgrum, GeNIe, Weka), or rename them"
        )
    out = [f"network {name} {{", "}"]
    for n in nodes:
        out += [
            f"variable {n} {{",
            f"  type discrete [ {len(values[n])} ] {{ {', '.join(values[n])} }};",
            "}",
        ]
    for n in nodes:
        ps = parents[n]
        cpt = cpts[n]
        if not ps:
            out += [f"probability ( {n} ) {{", "  table " + ", ".join(_num(p) for p in cpt) + ";", "}"]
            continue
        out.append(f"probability ( {n} | {', '.join(ps)} ) {{")
        for idx in np.ndindex(*cpt.shape[:-1]):
            config = ", ".join(values[p][i] for p, i in zip(ps, idx, strict=True))
            out.append(f"  ({config}) " + ", ".join(_num(p) for p in cpt[idx]) + ";")
        out.append("}")
    return "\n".join(out) + "\n"


def to_xmlbif(bn: BayesNet, zero_rows: str = "refuse", name: str = "glu") -> str:
    """The model as XMLBIF 0.3 text."""
    nodes, parents, cpts, values = _prepare(bn, zero_rows)
    root = ET.Element("BIF", VERSION="0.3")
    net = ET.SubElement(root, "NETWORK")
    ET.SubElement(net, "NAME").text = name
    for n in nodes:
        var = ET.SubElement(net, "VARIABLE", TYPE="nature")
        ET.SubElement(var, "NAME").text = n
        for v in values[n]:
            ET.SubElement(var, "OUTCOME").text = v
    for n in nodes:
        d = ET.SubElement(net, "DEFINITION")
        ET.SubElement(d, "FOR").text = n
        for p in parents[n]:
            ET.SubElement(d, "GIVEN").text = p
        ET.SubElement(d, "TABLE").text = " ".join(_num(p) for p in cpts[n].ravel())
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def to_uai(bn: BayesNet, zero_rows: str = "refuse") -> str:
    """The model as a UAI ``BAYES`` file (numbers only: nodes in glu's order, values by index)."""
    nodes, parents, cpts, values = _prepare(bn, zero_rows)
    index = {n: i for i, n in enumerate(nodes)}
    lines = ["BAYES", str(len(nodes)), " ".join(str(len(values[n])) for n in nodes), str(len(nodes))]
    for n in nodes:
        scope = [index[p] for p in parents[n]] + [index[n]]
        lines.append(" ".join(map(str, [len(scope), *scope])))
    for n in nodes:
        flat = cpts[n].ravel()
        lines += ["", str(flat.size), " " + " ".join(_num(p) for p in flat)]
    return "\n".join(lines) + "\n"


WRITERS = {"bif": to_bif, "xmlbif": to_xmlbif, "uai": to_uai}


def export_bn(
    bn: BayesNet, path: str | os.PathLike, fmt: str | None = None, zero_rows: str = "refuse"
) -> Path:
    """Write ``bn`` to ``path`` in ``fmt`` (default: from the suffix), atomically; returns the path."""
    fmt = format_of(path, fmt)
    return atomic_write_text(path, WRITERS[fmt](bn, zero_rows=zero_rows))


# ------------------------------------------------------------------ readers
def from_bif(text: str, where: str = "<string>", renormalise: float | None = None) -> BayesNet:
    """A model from BIF text (variables, then probability blocks with ``table``, ``default`` or one line per
    configuration), read in one pass over its tokens (:func:`glu.bn.bif.read_bif`: linear in its length)."""
    values, parents, cpts = read_bif(text, where)
    return assemble(
        values, parents, cpts, where, {"data_source": f"imported from {Path(where).name} (BIF)"}, renormalise
    )


def from_xmlbif(text: str, where: str = "<string>", renormalise: float | None = None) -> BayesNet:
    """A model from XMLBIF (0.3) text."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise ModelError(f"{where}: not XML ({e})") from None
    net = root.find("NETWORK")
    if net is None:
        raise ModelError(f"{where}: no <NETWORK> element (expected XMLBIF 0.3)")
    values: dict[str, tuple[str, ...]] = {}
    for var in net.findall("VARIABLE"):
        name = (var.findtext("NAME") or "").strip()
        if name in values:
            raise ModelError(f"{where}: variable {name!r} is declared twice")
        values[name] = tuple((o.text or "").strip() for o in var.findall("OUTCOME"))
    parents, cpts = {}, {}
    for d in net.findall("DEFINITION") + net.findall("PROBABILITY"):
        child = (d.findtext("FOR") or "").strip()
        ps = tuple((g.text or "").strip() for g in d.findall("GIVEN"))
        for n in (child, *ps):
            if n not in values:
                raise ModelError(f"{where}: the definition of {child!r} names an undeclared variable {n!r}")
        shape = tuple(len(values[p]) for p in ps) + (len(values[child]),)
        flat = np.array(numbers((d.findtext("TABLE") or "").split(), f"the table of {child!r}", where))
        if child in cpts:
            raise ModelError(f"{where}: two definitions of {child!r}")
        parents[child], cpts[child] = ps, table_from_flat(flat, shape, child, where, order="c")
    meta = {"data_source": f"imported from {Path(where).name} (XMLBIF)"}
    return assemble(values, parents, cpts, where, meta, renormalise)


def from_uai(text: str, where: str = "<string>", renormalise: float | None = None) -> BayesNet:
    """A model from a UAI ``BAYES`` file: nodes ``var_i``, values ``0 … k-1`` (UAI has no names)."""
    tokens = re.sub(r"#[^\n]*", " ", text).split()  # pyAgrum writes `# name` comments
    pos = 0

    def take(what: str) -> int:
        nonlocal pos
        if pos >= len(tokens):
            raise ModelError(f"{where}: the file ends early (expected {what})")
        tok = tokens[pos]
        pos += 1
        try:
            return int(tok)
        except ValueError:
            raise ModelError(f"{where}: expected {what} (an integer), found {tok!r}") from None

    if not tokens or tokens[0].upper() != "BAYES":
        raise ModelError(f"{where}: not a UAI Bayesian network (the first word must be BAYES)")
    pos = 1
    n = take("the number of variables")
    if n > len(tokens):  # each variable needs its cardinality in the file
        raise ModelError(f"{where}: declares {n:,} variables but the file has {len(tokens):,} numbers")
    cards = [check_declared(take("a cardinality"), "a variable's cardinality", where) for _ in range(n)]
    check_declared(sum(cards), "the variables' values", where)
    n_fun = take("the number of functions")
    if n_fun != n or n < 1 or min(cards, default=0) < 1:
        raise ModelError(
            f"{where}: {n} variables with cardinalities ≥ 1 need {n} functions, one CPT each; got {n_fun}"
        )
    scopes = []
    for _ in range(n_fun):
        k = take("a scope size")
        if k > len(tokens) - pos:
            raise ModelError(f"{where}: a scope of {k:,} variables is longer than the rest of the file")
        scopes.append([take("a variable index") for _ in range(k)])
    names = [f"var_{i}" for i in range(n)]
    values = {names[i]: tuple(str(v) for v in range(cards[i])) for i in range(n)}
    parents, cpts = {}, {}
    for scope in scopes:
        if not scope or any(not 0 <= i < n for i in scope):
            raise ModelError(f"{where}: a scope names variables outside 0 … {n - 1}: {scope}")
        child = names[scope[-1]]
        size = take(f"the table size of {child}")
        expected = check_declared(math.prod(cards[i] for i in scope), f"the table of {child!r}", where)
        if size != expected:
            raise ModelError(
                f"{where}: the table of {child!r} declares {size:,} numbers, expected {expected:,}"
            )
        if pos + size > len(tokens):
            raise ModelError(f"{where}: the table of {child!r} is cut short")
        flat = np.array(numbers(tokens[pos : pos + size], f"the table of {child!r}", where))
        pos += size
        if child in cpts:
            raise ModelError(f"{where}: two CPTs for {child!r} (the last variable of a scope is the child)")
        parents[child] = tuple(names[i] for i in scope[:-1])
        cpts[child] = table_from_flat(flat, tuple(cards[i] for i in scope), child, where, "c")
    return assemble(
        values, parents, cpts, where, {"data_source": f"imported from {Path(where).name} (UAI)"}, renormalise
    )


READERS = {"bif": from_bif, "xmlbif": from_xmlbif, "uai": from_uai}


def import_bn(path: str | os.PathLike, fmt: str | None = None, renormalise: float | None = None) -> BayesNet:
    """Read a BIF, XMLBIF or UAI file (format from the suffix unless ``fmt``), validated completely.

    ``renormalise``: rows whose sum is within this of 1 are rescaled to sum to 1 (default
    :data:`IMPORT_TOL`); the model's ``meta["renormalised"]`` reports how many, and the largest deviation.
    """
    path = Path(path)
    fmt = format_of(path, fmt)
    text = read_text(path, f"{fmt.upper()} file", error=ModelError)
    return READERS[fmt](text, str(path), renormalise)


# ------------------------------------------------------------------ assembling a BayesNet
def assemble(
    values: Mapping[str, tuple[str, ...]],
    parents: Mapping[str, tuple[str, ...]],
    cpts: Mapping[str, np.ndarray],
    where: str,
    meta: Mapping[str, Any] | None = None,
    renormalise: float | None = None,
) -> BayesNet:
    """A validated :class:`BayesNet` from any node order: indicators folded back, words last, parents sorted.

    Rows that sum to 1 within ``renormalise`` (default :data:`IMPORT_TOL`) are rescaled to sum to 1; when
    any is, ``meta["renormalised"]`` gives how many rows, the largest ``|1 − sum|``, where, and the
    tolerance.

    Raises :class:`ModelError` (naming ``where``) for a node without a CPT, a CPT for no node, duplicate
    values, wrong shapes, a cycle, a row that does not sum to 1 (naming the node and the parent values).
    """
    missing = [n for n in values if n not in cpts]
    if missing:
        raise ModelError(f"{where}: no probability table for {', '.join(missing[:5])}")
    if not values:
        raise ModelError(f"{where}: no variables")
    for n, vals in values.items():
        if not n or not vals or any(not v for v in vals) or len(set(vals)) != len(vals):
            raise ModelError(
                f"{where}: node {n!r} must have a name and distinct, non-empty value names; got {list(vals)}"
            )
    values, parents = dict(values), dict(parents)
    cpts = {n: np.asarray(c, dtype=float) for n, c in cpts.items()}
    tol = IMPORT_TOL if renormalise is None else renormalise
    cpts, report = normalise_rows(values, parents, cpts, tol, where)
    if report:
        meta = {**(meta or {}), "renormalised": report}
    _fold_indicators(values, parents, cpts, where)
    children = {p for ps in parents.values() for p in ps}
    named = any(v != tuple(str(i) for i in range(len(v))) for v in values.values())

    def is_word(n: str) -> bool:
        return n not in children and (values[n] == WORD_VALUES if named else True)

    if named:
        order = [n for n in values if not is_word(n)] + [n for n in values if is_word(n)]
        n_aff = sum(not is_word(n) for n in order)
    else:  # no names (UAI): keep the file's order; the core ends with the last node that has children
        order = list(values)
        n_aff = 1 + max((i for i, n in enumerate(order) if n in children), default=-1)
    rank = {n: i for i, n in enumerate(order)}
    sorted_parents, sorted_cpts = {}, {}
    for n in order:
        ps = parents[n]
        perm = sorted(range(len(ps)), key=lambda i: rank[ps[i]])
        sorted_parents[n] = tuple(ps[i] for i in perm)
        sorted_cpts[n] = np.transpose(cpts[n], [*perm, len(ps)]).copy()
    schema = Schema(values={n: values[n] for n in order}, n_affordance=n_aff, aliases=FILE_ALIASES)
    try:
        return BayesNet(schema=schema, parents=sorted_parents, cpts=sorted_cpts, meta=dict(meta or {}))
    except ModelError as e:
        raise ModelError(f"{where}: {e}") from None


def _fold_indicators(values: dict, parents: dict, cpts: dict, where: str) -> None:
    """Turn ``seen__X`` indicator nodes (see the module docstring) back into X's all-zero rows."""
    for name in [n for n in values if n.startswith(SEEN_PREFIX)]:
        node = name[len(SEEN_PREFIX) :]
        if node not in values or values[name] != SEEN_VALUES or parents[name] != parents[node]:
            continue
        if any(name in ps for ps in parents.values()):
            raise ModelError(f"{where}: the indicator {name!r} has children; an indicator must be a leaf")
        seen = cpts[name][..., 1]
        if not np.all((seen == 0) | (seen == 1)):
            raise ModelError(f"{where}: the indicator {name!r} must have P(yes) of 0 or 1 in every row")
        cpt = cpts[node].copy()
        cpt[seen == 0] = 0.0
        cpts[node] = cpt
        for d in (values, parents, cpts):
            del d[name]
