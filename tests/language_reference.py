"""Independent references for the language tests: grammar trees as plain tuples, their HParse text,
every sentence by direct expansion, and a plain scoring loop. Nothing here uses glu.language."""

from __future__ import annotations

import math
from fractions import Fraction

# A tree is ("w", word) | ("ref", name) | ("seq", [trees]) | ("alt", [trees]) | ("opt", tree)
# | ("star", tree) | ("plus", tree).


def to_text(tree) -> str:
    """HParse text of a tree (alternatives always bracketed inside sequences)."""
    kind, arg = tree
    if kind == "w":
        return arg
    if kind == "ref":
        return "$" + arg
    if kind == "seq":
        return " ".join("(" + to_text(t) + ")" if t[0] == "alt" else to_text(t) for t in arg)
    if kind == "alt":
        return " | ".join(to_text(t) for t in arg)
    if kind == "opt":
        return "[" + to_text(arg) + "]"
    if kind == "star":
        return "{" + to_text(arg) + "}"
    if kind == "plus":
        return "< " + to_text(arg) + " >"  # spaced: "<<" would be HParse's context loop
    raise ValueError(kind)


def grammar_text(sentence, definitions: dict | None = None) -> str:
    """A whole grammar: definitions, then the sentence in parentheses."""
    lines = [f"${k} = {to_text(v)};" for k, v in (definitions or {}).items()]
    return "\n".join([*lines, "(" + to_text(sentence) + ")"]) + "\n"


def expand(tree, definitions: dict | None = None, max_length: int = 50) -> set[tuple[str, ...]]:
    """Every sentence of a tree of at most ``max_length`` words, by direct expansion (brute force)."""
    defs = definitions or {}

    def cat(a: set, b: set) -> set:
        return {x + y for x in a for y in b if len(x) + len(y) <= max_length}

    def star(base: set) -> set:
        out = {()}
        frontier = {()}
        while frontier:
            frontier = cat(frontier, base) - out
            out |= frontier
        return out

    def go(t) -> set:
        kind, arg = t
        if kind == "w":
            return {(arg,)} if max_length >= 1 else set()
        if kind == "ref":
            return go(defs[arg])
        if kind == "seq":
            out = {()}
            for item in arg:
                out = cat(out, go(item))
            return out
        if kind == "alt":
            return set().union(*(go(x) for x in arg))
        if kind == "opt":
            return go(arg) | {()}
        if kind == "star":
            return star(go(arg))
        if kind == "plus":
            base = go(arg)
            return cat(base, star(base))
        raise ValueError(kind)

    return go(tree)


SCALE = 2**1100  # every finite double times this is an integer: exact sums without Fractions
LENGTHS_LCM = math.lcm(*range(1, 65))  # compares means of different lengths exactly, in integers


def exact_logs(probs: dict[str, float]) -> dict[str, int | None]:
    """log p(w) × 2^1100 as exact integers (None for p = 0)."""
    return {w: None if p == 0 else int(Fraction(math.log(p)) * SCALE) for w, p in probs.items()}


def exact_key(sentence: tuple[str, ...], logs: dict[str, int | None], start: int = 0):
    """The documented ranking key: (zero-probability words, −exact (start + Σ other logs)/L, words).

    ``start`` is where the sum starts: 0 for the papers' score, 1 for the originals' code.
    """
    n_zero = sum(1 for w in sentence if logs[w] is None)
    total = start * SCALE + sum(logs[w] for w in sentence if logs[w] is not None)
    return (n_zero, -total * (LENGTHS_LCM // len(sentence)), sentence)


def plain_score(sentence: tuple[str, ...], probs: dict[str, float], start: float = 0.0) -> float:
    """(start + Σ log p(w)) / L with a plain loop; -inf when a word has probability 0."""
    s = start
    for w in sentence:
        if probs[w] == 0:
            return -math.inf
        s += math.log(probs[w])
    return s / len(sentence)


def brute_force_nbest(
    sentences, probs: dict[str, float], n: int, start: int = 0
) -> list[tuple[tuple[str, ...], float]]:
    """The n best non-empty sentences by the documented key, with their plain scores (sums from ``start``)."""
    logs = exact_logs(probs)
    ranked = sorted((s for s in sentences if s), key=lambda s: exact_key(s, logs, start))
    return [(s, plain_score(s, probs, start)) for s in ranked[:n]]


def recursive_samples(grammar, n: int, seed: int) -> list[tuple[str, ...]]:
    """The sampler as first written: a recursive walk of the grammar tree (the draws the originals' HSGen
    makes, in their order), the reference for the compiled walk of glu.language.sampling (tests and
    benchmarks/bench_fast_paths.py)."""
    import random

    from glu.language.grammar import Alt, Opt, Ref, Rep, Seq, Word

    rng = random.Random(seed)

    def gen(e, out):
        if isinstance(e, Word):
            out.append(e.text)
        elif isinstance(e, Ref):
            gen(grammar.definitions[e.name], out)
        elif isinstance(e, Seq):
            for item in e.items:
                gen(item, out)
        elif isinstance(e, Alt):
            gen(e.options[rng.randrange(len(e.options))], out)
        elif isinstance(e, Opt):
            if rng.random() < 0.5:
                gen(e.expr, out)
        elif isinstance(e, Rep):
            if e.at_least_one:
                gen(e.expr, out)
            while rng.random() < 0.5:
                gen(e.expr, out)

    result = []
    for _ in range(n):
        out: list[str] = []
        gen(grammar.sentence, out)
        result.append(tuple(out))
    return result
