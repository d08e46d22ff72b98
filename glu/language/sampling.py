"""Random sentences of a grammar, as the originals drew them (HTK's HSGen), and their probability.

:func:`sample_sentences` walks the grammar, choosing uniformly at random at each alternative, tossing a
fair coin at each optional part and before each further repetition. It follows the grammar, not the word
network, so a sentence's chance depends on how the grammar is written; :func:`sample_probability` gives
that chance exactly.
"""

from __future__ import annotations

import random
import sys
from collections.abc import Callable, Iterable

from glu.errors import GrammarError
from glu.language.grammar import Alt, Expr, Grammar, Opt, Ref, Rep, Seq, Word
from glu.language.sentences import Sentence, as_sentence

MAX_SAMPLE_WORDS = 10_000
"""A random sentence longer than this (possible only with repetitions) raises GrammarError."""
MAX_SAMPLES = 200_000
"""At most this many random sentences at once (20× the originals' 10,000; about 80 MB with their scores)."""


def sample_sentences(grammar: Grammar, n: int, seed: int | None = 0) -> list[Sentence]:
    """``n`` random sentences as HTK's HSGen makes them (uniform alternatives, fair coins); seeded, may
    repeat.

    Parameters
    ----------
    grammar : the grammar to walk
    n : number of sentences, at most :data:`MAX_SAMPLES`
    seed : seed of the random generator (Python's ``random.Random``); the same seed gives the same list

    Returns
    -------
    list of ``n`` sentences, each a tuple of words
    """
    if int(n) != n or n < 0:
        raise GrammarError(f"the number of sentences must be a whole number ≥ 0, not {n!r}", grammar.source)
    if n > MAX_SAMPLES:
        raise GrammarError(
            f"{n:,} random sentences: at most {MAX_SAMPLES:,} at once (memory grows with each; "
            "the originals drew 10,000)",
            grammar.source,
        )
    rng = random.Random(seed)
    result: list[Sentence] = []
    try:
        walk = _compile(grammar.sentence, grammar, rng.random, rng.randrange, {})
        for _ in range(int(n)):
            out: list[str] = []
            walk(out)
            result.append(tuple(out))
    except RecursionError:
        raise GrammarError(
            "the grammar nests too deeply to draw sentences from (variables within variables, "
            f"deeper than Python's recursion limit of {sys.getrecursionlimit()})",
            grammar.source,
        ) from None
    return result


Walk = Callable[[list[str]], None]


def _compile(
    e: Expr,
    grammar: Grammar,
    rand: Callable[[], float],
    randrange: Callable[[int], int],
    refs: dict[str, Walk],
) -> Walk:
    """A function that appends one random expansion of ``e`` to a list, drawing exactly as the recursive
    walk of the grammar does (the same calls to ``rand`` and ``randrange``, in the same order), with the
    grammar's structure resolved once instead of at every word. Runs of words become one ``extend``."""
    if isinstance(e, Word):
        text = e.text
        return lambda out: out.append(text)
    if isinstance(e, Ref):
        if e.name not in refs:  # the parser refuses recursive definitions: this terminates
            refs[e.name] = _compile(grammar.definitions[e.name], grammar, rand, randrange, refs)
        return refs[e.name]
    if isinstance(e, Seq):
        parts: list[Walk | tuple[str, ...]] = []
        for item in e.items:
            if isinstance(item, Word) and parts and isinstance(parts[-1], tuple):
                parts[-1] += (item.text,)
            else:
                parts.append(
                    (item.text,) if isinstance(item, Word) else _compile(item, grammar, rand, randrange, refs)
                )
        steps = [(lambda out, w=p: out.extend(w)) if isinstance(p, tuple) else p for p in parts]
        if len(steps) == 1:
            return steps[0]

        def seq(out: list[str]) -> None:
            for step in steps:
                step(out)

        return seq
    if isinstance(e, Alt):
        n = len(e.options)
        if all(isinstance(o, Word) for o in e.options):
            texts = [o.text for o in e.options]
            return lambda out: out.append(texts[randrange(n)])
        options = [_compile(o, grammar, rand, randrange, refs) for o in e.options]
        return lambda out: options[randrange(n)](out)
    if isinstance(e, Opt):
        inner = _compile(e.expr, grammar, rand, randrange, refs)

        def opt(out: list[str]) -> None:
            if rand() < 0.5:
                inner(out)

        return opt
    inner = _compile(e.expr, grammar, rand, randrange, refs)  # Rep, the last kind of expression
    at_least_one = e.at_least_one

    def rep(out: list[str]) -> None:
        if at_least_one:
            inner(out)
        while rand() < 0.5:
            inner(out)
            if len(out) > MAX_SAMPLE_WORDS:
                raise GrammarError(f"a random sentence grew beyond {MAX_SAMPLE_WORDS} words", grammar.source)

    return rep


def sample_probability(grammar: Grammar, sentence: str | Iterable[str]) -> float:
    """The probability that one sentence of :func:`sample_sentences` is ``sentence`` (0 if not in the
    grammar).

    Sums over every derivation (a chart over word positions); a repetition stops with probability 1/2
    before each further round, as in the sampler. So ``1 - (1 - p)**K`` is the chance that K random
    sentences contain ``sentence``.
    """
    words = as_sentence(sentence)
    n = len(words)
    defs = grammar.definitions
    memo: dict[tuple[int, int], dict[int, float]] = {}

    def add(acc: dict[int, float], dist: dict[int, float], w: float) -> None:
        for j, p in dist.items():
            acc[j] = acc.get(j, 0.0) + w * p

    def star(body: Expr, i: int, cache: dict[int, dict[int, float]]) -> dict[int, float]:
        """End positions of zero or more rounds of ``body`` from i: stop (1/2) or one more round (1/2)."""
        if i in cache:
            return cache[i]
        step = parse(body, i)
        b0 = step.get(i, 0.0)  # a round that consumes no word
        acc = {i: 0.5}
        for j, p in step.items():
            if j > i:
                add(acc, star(body, j, cache), 0.5 * p)
        out = {j: p / (1 - 0.5 * b0) for j, p in acc.items()}
        cache[i] = out
        return out

    rep_caches: dict[int, dict[int, dict[int, float]]] = {}

    def parse(e: Expr, i: int) -> dict[int, float]:
        key = (id(e), i)
        if key in memo:
            return memo[key]
        acc: dict[int, float] = {}
        if isinstance(e, Word):
            if i < n and words[i] == e.text:
                acc[i + 1] = 1.0
        elif isinstance(e, Ref):
            acc = parse(defs[e.name], i)
        elif isinstance(e, Seq):
            acc = {i: 1.0}
            for item in e.items:
                nxt: dict[int, float] = {}
                for k, p in acc.items():
                    add(nxt, parse(item, k), p)
                acc = nxt
        elif isinstance(e, Alt):
            for option in e.options:
                add(acc, parse(option, i), 1.0 / len(e.options))
        elif isinstance(e, Opt):
            acc[i] = 0.5
            add(acc, parse(e.expr, i), 0.5)
        elif isinstance(e, Rep):
            cache = rep_caches.setdefault(id(e), {})
            if e.at_least_one:
                for j, p in parse(e.expr, i).items():
                    add(acc, star(e.expr, j, cache), p)
            else:
                acc = star(e.expr, i, cache)
        memo[key] = acc
        return acc

    try:
        return float(parse(grammar.sentence, 0).get(n, 0.0))
    except RecursionError:
        raise GrammarError(
            "the sentence is too long or the grammar nests too deeply", grammar.source
        ) from None
