"""Reading BIF text in one pass, and the size limit every exchange reader checks before allocating.

:func:`read_bif` splits the text into tokens with one regular expression applied once at each position
(comments dropped; an unclosed ``/*`` is found with one search), then walks the tokens forward only, so the
time is linear in the length of the file (``benchmarks/bench_bif_import.py``: 100,000 lines in about a
second). An earlier reader matched a pattern per block that, on a block never closed, searched to the end
of the file from every ``variable``: quadratic, 13.7 s for 8,000 lines. Value names are looked up in
dictionaries, not lists. :func:`check_declared` refuses a declared size above :data:`MAX_DECLARED` before
anything of that size is allocated. :mod:`glu.bn.exchange` turns what is read into a validated model.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence

import numpy as np

from glu.errors import ModelError

MAX_DECLARED = 1 << 24
"""The largest table (entries) or number of values a file may declare: checked before anything of that
size is allocated, so a file declaring 10⁹ values is refused in one line instead of exhausting memory."""


def check_declared(n: int, what: str, where: str) -> int:
    """``n`` when it is at most :data:`MAX_DECLARED`; else :class:`ModelError` naming ``what`` and the
    size."""
    if n > MAX_DECLARED:
        raise ModelError(f"{where}: {what} declares {n:,} entries; glu reads at most {MAX_DECLARED:,}")
    return n


_BIF_TOKEN = re.compile(r"\s+|//[^\n]*|/\*|[{}()\[\];,|]|(?:[^\s{}()\[\];,|/]|/(?![/*]))+")


def _bif_tokens(text: str, where: str) -> list[str]:
    """BIF's tokens in one pass: words and numbers, punctuation; comments and white space dropped."""
    tokens, pos, n, match = [], 0, len(text), _BIF_TOKEN.match
    while pos < n:
        m = match(text, pos)
        tok = m.group()  # the pattern matches any character: a lone "/" is a word
        if tok == "/*":
            end = text.find("*/", pos + 2)
            if end < 0:
                raise ModelError(f"{where}: a /* comment is never closed")
            pos = end + 2
            continue
        pos = m.end()
        if not (tok[0].isspace() or tok.startswith("//")):
            tokens.append(tok)
    return tokens


class _BifReader:
    """A cursor over BIF tokens; every step moves forward, so reading is linear in the file."""

    def __init__(self, tokens: list[str], where: str):
        self.tokens, self.i, self.where = tokens, 0, where

    def next(self, what: str) -> str:
        if self.i >= len(self.tokens):
            raise ModelError(f"{self.where}: the file ends early (expected {what})")
        self.i += 1
        return self.tokens[self.i - 1]

    def peek(self) -> str | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def expect(self, tok: str, context: str) -> None:
        got = self.next(repr(tok))
        if got != tok:
            raise ModelError(f"{self.where}: {context}: expected {tok!r}, found {got!r}")

    def until(self, stop: str, what: str) -> list[str]:
        """The tokens up to ``stop`` (consumed), commas dropped."""
        out = []
        while True:
            tok = self.next(f"{what} ending with {stop!r}")
            if tok == stop:
                return out
            if tok != ",":
                out.append(tok)

    def skip_block(self, context: str) -> None:
        self.expect("{", context)
        depth = 1
        while depth:
            tok = self.next("'}'")
            depth += {"{": 1, "}": -1}.get(tok, 0)


def numbers(tokens: list[str], context: str, where: str) -> list[float]:
    """The numbers of ``tokens``, or :class:`ModelError` naming ``context`` for a malformed one."""
    try:
        return [float(t) for t in tokens]
    except ValueError as e:
        raise ModelError(f"{where}: {context}: malformed number ({e})") from None


def _bif_variable(r: _BifReader, name: str) -> tuple[str, ...]:
    where, context = r.where, f"variable {name!r}"
    r.expect("{", context)
    vals: tuple[str, ...] | None = None
    while (tok := r.next("'}'")) != "}":
        if tok == "type":
            bad = ModelError(f"{where}: variable {name!r} is not 'type discrete [ n ] {{ values }}'")
            if r.next("discrete") != "discrete" or r.next("[") != "[":
                raise bad
            n = r.next("the number of values")
            if not n.isdigit() or r.next("]") != "]" or r.next("{") != "{":
                raise bad
            check_declared(int(n), context, where)
            vals = tuple(r.until("}", "the values"))
            if len(vals) != int(n):
                raise ModelError(f"{where}: variable {name!r} declares {n} values but lists {len(vals)}")
            if r.peek() == ";":
                r.next(";")
        elif tok == "property":
            r.until(";", "a property")
        else:
            raise ModelError(f"{where}: {context}: expected 'type' or 'property', found {tok!r}")
    if vals is None:
        raise ModelError(f"{where}: variable {name!r} is not 'type discrete [ n ] {{ values }}'")
    return vals


def _bif_probability(
    r: _BifReader, values: Mapping[str, tuple[str, ...]], index: Mapping[str, Mapping[str, int]]
) -> tuple[str, tuple[str, ...], np.ndarray]:
    where = r.where
    r.expect("(", "probability")
    head = r.until(")", "the probability's variables")
    if not head or (len(head) > 1 and head[1] != "|") or "|" in head[2:]:
        raise ModelError(f"{where}: malformed 'probability ( {' '.join(head)} )'")
    child, ps = head[0], tuple(head[2:])
    for n in (child, *ps):
        if n not in values:
            raise ModelError(f"{where}: probability of {child!r} names an undeclared variable {n!r}")
    shape = tuple(len(values[p]) for p in ps) + (len(values[child]),)
    check_declared(math.prod(shape), f"the table of {child!r}", where)
    cpt = np.full(shape, np.nan)
    context = f"probability of {child!r}"
    r.expect("{", context)
    while (tok := r.next("'}'")) != "}":
        if tok == "table":
            cpt = table_from_flat(
                np.array(numbers(r.until(";", "a table"), context, where)),
                shape,
                child,
                where,
                "parents-slowest",
            )
        elif tok == "default":
            row = numbers(r.until(";", "a default row"), context, where)
            if len(row) != shape[-1]:
                raise ModelError(f"{where}: {context}: a row has {len(row)} numbers, expected {shape[-1]}")
            cpt[np.isnan(cpt).all(axis=-1)] = row
        elif tok == "(":
            config = r.until(")", "a configuration")
            if len(config) != len(ps):
                raise ModelError(
                    f"{where}: {context}: the configuration ({', '.join(config)}) names {len(config)} "
                    f"value(s) for {len(ps)} parent(s)"
                )
            idx = tuple(
                _value_index(index[p], values[p], v, p, where) for p, v in zip(ps, config, strict=True)
            )
            row = numbers(r.until(";", "a row"), context, where)
            if len(row) != shape[-1]:
                raise ModelError(f"{where}: {context}: a row has {len(row)} numbers, expected {shape[-1]}")
            cpt[idx] = row
        elif tok == "property":
            r.until(";", "a property")
        else:
            raise ModelError(
                f"{where}: {context}: expected 'table', 'default', '(' or 'property', found {tok!r}"
            )
    return child, ps, cpt


def _value_index(index: Mapping[str, int], vals: Sequence[str], v: str, node: str, where: str) -> int:
    try:
        return index[v]
    except KeyError:
        shown = ", ".join(vals[:20]) + (", …" if len(vals) > 20 else "")
        raise ModelError(f"{where}: {node!r} has no value {v!r}; values: {shown}") from None


def table_from_flat(
    flat: np.ndarray, shape: tuple[int, ...], node: str, where: str, order: str
) -> np.ndarray:
    """The table of ``node`` of ``shape`` (parents' axes, then the node's) from its numbers in file order:
    ``"parents-slowest"`` (BIF's ``table``) or ``"c"`` (XMLBIF, UAI); ModelError when the count is wrong."""
    if flat.size != math.prod(shape):
        raise ModelError(
            f"{where}: the table of {node!r} has {flat.size} numbers, expected {math.prod(shape):,}"
        )
    if order == "parents-slowest":  # BIF's `table`: the child's values vary slowest (pgmpy, bnlearn)
        return np.moveaxis(flat.reshape((shape[-1], *shape[:-1])), 0, -1)
    return flat.reshape(shape)


def read_bif(text: str, where: str = "<string>") -> tuple[dict, dict, dict]:
    """The variables' values, each node's parents and its table (parents' axes first, NaN where no row was
    given) of BIF text: variables, then probability blocks with ``table``, ``default`` or one line per
    configuration; read in one pass over its tokens, so linear in the text's length."""
    r = _BifReader(_bif_tokens(text, where), where)
    values: dict[str, tuple[str, ...]] = {}
    index: dict[str, dict[str, int]] = {}
    parents: dict[str, tuple[str, ...]] = {}
    cpts: dict[str, np.ndarray] = {}
    while r.peek() is not None:
        kw = r.next("a block")
        if kw == "network":
            r.next("the network's name")
            r.skip_block("network")
        elif kw == "variable":
            name = r.next("a variable name")
            vals = _bif_variable(r, name)
            if name in values:
                raise ModelError(f"{where}: variable {name!r} is declared twice")
            values[name] = vals
            index[name] = {v: k for k, v in enumerate(vals)}
        elif kw == "probability":
            child, ps, cpt = _bif_probability(r, values, index)
            if child in cpts:
                raise ModelError(f"{where}: two probability blocks for {child!r}")
            parents[child], cpts[child] = ps, cpt
        else:
            raise ModelError(f"{where}: expected 'network', 'variable' or 'probability', found {kw!r}")
    return values, parents, cpts
