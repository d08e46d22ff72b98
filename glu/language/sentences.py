"""The sentences of a grammar: a deterministic word network, counting and enumeration.

:func:`compile_network` turns a :class:`~glu.language.grammar.Grammar` into a :class:`WordNetwork`, a
deterministic finite automaton over words (Thompson construction, then subset construction, then the
states that cannot end a sentence are removed). In a deterministic network every path is a different
sentence, so counting paths counts *sentences* (not derivations: ``[a] [a]`` has three derivations but two
sentences, ``a`` and ``a a``), enumeration never repeats, and the exact N-best of
:mod:`glu.language.descriptions` is a k-best search over its paths.

Random generation (the originals' method) is in :mod:`glu.language.sampling`.

Example
-------
>>> from glu.language import load_grammar, compile_network, count_sentences
>>> count_sentences(compile_network(load_grammar()))
9331200
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property

from glu.errors import GrammarError
from glu.language.grammar import Alt, Expr, Grammar, Opt, Ref, Rep, Seq, Word, children

MAX_NFA_ARCS = 1_000_000
"""Largest grammar accepted, in words after substituting every variable (guards against blow-ups)."""
MAX_DFA_STATES = 200_000
"""Largest deterministic network built."""

Sentence = tuple[str, ...]


def as_sentence(sentence: str | Iterable[str]) -> Sentence:
    """A sentence as a tuple of words, from a string of words separated by spaces or a sequence of words."""
    return tuple(sentence.split()) if isinstance(sentence, str) else tuple(sentence)


@dataclass(frozen=True, eq=False)
class WordNetwork:
    """A deterministic word network: the sentences of a grammar are the paths from ``start`` to a final state.

    Attributes
    ----------
    words : the vocabulary, sorted; arcs refer to words by index into it
    arcs : per state, ``((word index, next state), …)`` sorted by word; shape (n_states,) of tuples
    final : per state, whether a sentence may end there; shape (n_states,)
    start : the initial state
    source : where the grammar came from
    """

    words: tuple[str, ...]
    arcs: tuple[tuple[tuple[int, int], ...], ...]
    final: tuple[bool, ...]
    start: int
    source: str = "<string>"

    @property
    def n_states(self) -> int:
        """Number of states."""
        return len(self.arcs)

    @cached_property
    def topological_order(self) -> tuple[int, ...] | None:
        """States in an order where every arc goes forward, or None when the network has a cycle."""
        indeg = [0] * self.n_states
        for arcs in self.arcs:
            for _, t in arcs:
                indeg[t] += 1
        todo = deque(s for s in range(self.n_states) if indeg[s] == 0)
        order: list[int] = []
        while todo:
            s = todo.popleft()
            order.append(s)
            for _, t in self.arcs[s]:
                indeg[t] -= 1
                if indeg[t] == 0:
                    todo.append(t)
        return tuple(order) if len(order) == self.n_states else None

    @property
    def is_finite(self) -> bool:
        """True when the network accepts finitely many sentences (it has no cycle)."""
        return self.topological_order is not None

    @cached_property
    def min_remaining(self) -> tuple[float, ...]:
        """Per state, the fewest words to a final state (0 at a final state)."""
        inf = float("inf")
        dist = [0.0 if f else inf for f in self.final]
        preds: list[list[int]] = [[] for _ in range(self.n_states)]
        for s, arcs in enumerate(self.arcs):
            for _, t in arcs:
                preds[t].append(s)
        todo = deque(s for s in range(self.n_states) if self.final[s])
        while todo:
            t = todo.popleft()
            for s in preds[t]:
                if dist[s] == inf:
                    dist[s] = dist[t] + 1
                    todo.append(s)
        return tuple(dist)

    @property
    def min_length(self) -> int:
        """Words in the shortest sentence."""
        return int(self.min_remaining[self.start])

    @cached_property
    def max_length(self) -> int | None:
        """Words in the longest sentence, or None for an infinite network."""
        order = self.topological_order
        if order is None:
            return None
        longest = [0] * self.n_states
        for s in reversed(order):
            longest[s] = max((1 + longest[t] for _, t in self.arcs[s]), default=0)
        return longest[self.start]

    def check_length_limit(self, max_length: int | None) -> int:
        """The length limit to use: ``max_length``, or the longest sentence; GrammarError for an infinite
        network without one."""
        if max_length is None:
            if self.max_length is None:
                raise GrammarError(
                    "the grammar has infinitely many sentences (it uses { } or < >); give a maximum length "
                    "(max_length=…, or --max-length on the command line)",
                    self.source,
                )
            return self.max_length
        if int(max_length) != max_length or max_length < 0:
            raise GrammarError(
                f"the maximum length must be a whole number ≥ 0, not {max_length!r}", self.source
            )
        return int(max_length)

    def accepts(self, sentence: str | Iterable[str]) -> bool:
        """Whether ``sentence`` (a string of words separated by spaces, or a sequence of words) is in the
        language."""
        words = as_sentence(sentence)
        index = {w: i for i, w in enumerate(self.words)}
        s = self.start
        for w in words:
            i = index.get(w)
            nxt = next((t for j, t in self.arcs[s] if j == i), None) if i is not None else None
            if nxt is None:
                return False
            s = nxt
        return self.final[s]


# ---------------------------------------------------------------------------------------- construction
def _expanded_size(grammar: Grammar) -> int:
    """Number of word occurrences once every variable is substituted (without building anything)."""
    memo: dict[str, int] = {}

    def size(e: Expr) -> int:
        if isinstance(e, Word):
            return 1
        if isinstance(e, Ref):
            if e.name not in memo:
                memo[e.name] = size(grammar.definitions[e.name])
            return memo[e.name]
        return sum(size(x) for x in children(e))

    return size(grammar.sentence)


def compile_network(grammar: Grammar) -> WordNetwork:
    """The deterministic word network of ``grammar`` (see the module docstring); GrammarError if too large."""
    try:
        n_words = _expanded_size(grammar)
    except RecursionError:
        raise GrammarError("the grammar nests variables too deeply to expand", grammar.source) from None
    if n_words > MAX_NFA_ARCS:
        raise GrammarError(
            f"the grammar expands to {n_words} words once variables are substituted; "
            f"glu handles up to {MAX_NFA_ARCS}",
            grammar.source,
        )
    vocab = grammar.vocabulary
    eps, trans, s0, t0 = _thompson(grammar, {w: i for i, w in enumerate(vocab)})
    dfa_arcs, final = _subsets(eps, trans, s0, t0, grammar.source)
    return _trim(vocab, dfa_arcs, final, 0, grammar.source)


def _thompson(grammar: Grammar, index: dict[str, int]) -> tuple[list, list, int, int]:
    """Thompson's construction: (epsilon arcs, word arcs (word, target) per state, start, end)."""
    eps: list[list[int]] = []
    trans: list[list[tuple[int, int]]] = []

    def new() -> int:
        eps.append([])
        trans.append([])
        return len(eps) - 1

    def build(e: Expr, s: int, t: int) -> None:
        if isinstance(e, Word):
            trans[s].append((index[e.text], t))
        elif isinstance(e, Ref):
            build(grammar.definitions[e.name], s, t)
        elif isinstance(e, Seq):
            cur = s
            for k, item in enumerate(e.items):
                nxt = t if k == len(e.items) - 1 else new()
                build(item, cur, nxt)
                cur = nxt
        elif isinstance(e, Alt):
            for option in e.options:
                build(option, s, t)
        elif isinstance(e, Opt):
            build(e.expr, s, t)
            eps[s].append(t)
        elif isinstance(e, Rep):
            a, b = new(), new()
            eps[s].append(a)
            build(e.expr, a, b)
            eps[b].append(a)
            eps[b if e.at_least_one else a].append(t)
        else:  # pragma: no cover
            raise TypeError(f"not a grammar expression: {e!r}")

    s0, t0 = new(), new()
    try:
        build(grammar.sentence, s0, t0)
    except RecursionError:
        raise GrammarError("the grammar nests too deeply to compile", grammar.source) from None
    return eps, trans, s0, t0


def _reachable(states: Iterable[int], arcs: Sequence[Iterable[int]]) -> set[int]:
    """The states reachable from ``states`` (themselves included) along ``arcs`` (state → next states)."""
    seen = set(states)
    stack = list(seen)
    while stack:
        for t in arcs[stack.pop()]:
            if t not in seen:
                seen.add(t)
                stack.append(t)
    return seen


def _subsets(
    eps: list, trans: list, s0: int, t0: int, source: str
) -> tuple[list[dict[int, int]], list[bool]]:
    """The subset construction: the deterministic arcs from state 0 (the start's closure), and which states
    are final; GrammarError past :data:`MAX_DFA_STATES`."""

    def closure(states: Iterable[int]) -> frozenset[int]:
        return frozenset(_reachable(states, eps))

    start = closure([s0])
    ids: dict[frozenset[int], int] = {start: 0}
    subsets = [start]
    dfa_arcs: list[dict[int, int]] = []
    k = 0
    while k < len(subsets):
        moves: dict[int, set[int]] = {}
        for q in subsets[k]:
            for w, t in trans[q]:
                moves.setdefault(w, set()).add(t)
        out: dict[int, int] = {}
        for w, targets in moves.items():
            c = closure(targets)
            if c not in ids:
                if len(subsets) >= MAX_DFA_STATES:
                    raise GrammarError(
                        f"the grammar's word network needs more than {MAX_DFA_STATES} states", source
                    )
                ids[c] = len(subsets)
                subsets.append(c)
            out[w] = ids[c]
        dfa_arcs.append(out)
        k += 1
    return dfa_arcs, [t0 in sub for sub in subsets]


def _trim(
    words: tuple[str, ...], arcs: list[dict[int, int]], final: list[bool], start: int, source: str
) -> WordNetwork:
    """Keep the states reachable from ``start`` that can reach a final state; renumber breadth-first."""
    preds: list[list[int]] = [[] for _ in arcs]
    for s, out in enumerate(arcs):
        for t in out.values():
            preds[t].append(s)
    alive = _reachable((s for s, f in enumerate(final) if f), preds)
    if start not in alive:  # the language is empty: keep one non-final state
        return WordNetwork(words, ((),), (False,), 0, source)
    new_id = {start: 0}  # breadth-first order
    kept: dict[int, list[tuple[int, int]]] = {}  # per state, its arcs into live states, in word order
    queue = deque([start])
    while queue:
        s = queue.popleft()
        kept[s] = [(w, arcs[s][w]) for w in sorted(arcs[s], key=lambda i: words[i]) if arcs[s][w] in alive]
        for _, t in kept[s]:
            if t not in new_id:
                new_id[t] = len(new_id)
                queue.append(t)
    new_arcs = tuple(tuple((w, new_id[t]) for w, t in kept[s]) for s in new_id)
    return WordNetwork(words, new_arcs, tuple(final[s] for s in new_id), 0, source)


def restrict(
    net: WordNetwork, must_contain: Iterable[str] | None = None, exclude: Iterable[str] | None = None
) -> WordNetwork:
    """The sentences of ``net`` with at least one word of ``must_contain`` and none of ``exclude``."""
    index = {w: i for i, w in enumerate(net.words)}
    banned = {index[w] for w in (exclude or ()) if w in index}
    if must_contain is None:
        arcs = [{w: t for w, t in a if w not in banned} for a in net.arcs]
        return _trim(net.words, arcs, list(net.final), net.start, net.source)
    wanted = {index[w] for w in must_contain if w in index}
    # product with a flag "a wanted word has been seen": state (s, seen) → 2 s + seen
    arcs2: list[dict[int, int]] = [{} for _ in range(2 * net.n_states)]
    for s, a in enumerate(net.arcs):
        for w, t in a:
            if w in banned:
                continue
            arcs2[2 * s][w] = 2 * t + (w in wanted)
            arcs2[2 * s + 1][w] = 2 * t + 1
    final2 = [seen == 1 and net.final[s] for s in range(net.n_states) for seen in (0, 1)]
    return _trim(net.words, arcs2, final2, 2 * net.start, net.source)


def same_language(a: WordNetwork, b: WordNetwork) -> bool:
    """True when the two networks accept exactly the same sentences (breadth-first over state pairs)."""
    da = [{a.words[w]: t for w, t in arcs} for arcs in a.arcs]
    db = [{b.words[w]: t for w, t in arcs} for arcs in b.arcs]
    seen = {(a.start, b.start)}
    queue = deque(seen)
    while queue:
        x, y = queue.popleft()
        fx = x >= 0 and a.final[x]
        fy = y >= 0 and b.final[y]
        if fx != fy:
            return False
        out_x = da[x] if x >= 0 else {}
        out_y = db[y] if y >= 0 else {}
        for w in set(out_x) | set(out_y):
            pair = (out_x.get(w, -1), out_y.get(w, -1))
            if pair not in seen:
                seen.add(pair)
                queue.append(pair)
    return True


def as_network(grammar_or_net: Grammar | WordNetwork) -> WordNetwork:
    """A WordNetwork, compiling a Grammar if needed."""
    if isinstance(grammar_or_net, WordNetwork):
        return grammar_or_net
    if isinstance(grammar_or_net, Grammar):
        return compile_network(grammar_or_net)
    raise TypeError(f"expected a Grammar or a WordNetwork, not {type(grammar_or_net).__name__}")


# -------------------------------------------------------------------------------- counting, enumerating
def count_by_length(grammar: Grammar | WordNetwork, max_length: int | None = None) -> dict[int, int]:
    """Number of sentences of each length (in words), for lengths up to ``max_length``; zero counts left
    out."""
    net = as_network(grammar)
    limit = net.check_length_limit(max_length)
    # cnt[l][s] = sentences of exactly l words from state s
    cur = [1 if f else 0 for f in net.final]
    out = {0: cur[net.start]}
    for length in range(1, limit + 1):
        cur = [sum(cur[t] for _, t in arcs) for arcs in net.arcs]
        out[length] = cur[net.start]
        if not any(cur):
            break
    return {k: v for k, v in out.items() if v}


def count_sentences(grammar: Grammar | WordNetwork, max_length: int | None = None) -> int:
    """Number of distinct sentences (up to ``max_length`` words; required when the grammar is infinite)."""
    return sum(count_by_length(grammar, max_length).values())


def enumerate_sentences(grammar: Grammar | WordNetwork, max_length: int | None = None) -> Iterator[Sentence]:
    """Every sentence once, in lexicographic order of the word sequence (up to ``max_length`` words)."""
    net = as_network(grammar)
    limit = net.check_length_limit(max_length)
    rem = net.min_remaining
    # depth-first, arcs in word order; a final state yields its sentence before its extensions
    stack: list[tuple[int, Sentence]] = [(net.start, ())]
    while stack:
        s, words = stack.pop()
        if net.final[s]:
            yield words
        if len(words) >= limit:
            continue
        for w, t in reversed(net.arcs[s]):
            if len(words) + 1 + rem[t] <= limit:
                stack.append((t, (*words, net.words[w])))
