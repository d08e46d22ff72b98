"""The grammar of the verbal descriptions: a parser for HTK's HParse syntax.

A grammar is a list of variable definitions followed by the sentence, in parentheses::

    $agent = the robot | he | baltazar;       /* alternatives */
    $object = the [$size] [$color] $shape;    /* [ ] optional */
    ( $agent $action $object $conjunction $object $effect )

Factors are words, ``$variables``, ``( … )`` (grouping), ``[ … ]`` (optional), ``{ … }`` (zero or more
repetitions) and ``< … >`` (one or more). C comments ``/* … */`` may appear anywhere; a backslash escapes
a meta character inside a word; ``word%external`` keeps the word (HParse's external name is ignored).
HParse's ``<< … >>`` context loops are not supported. Unlike HParse, glu accepts a variable used before
its definition; a variable that refers to itself, directly or through others, is an error (HParse would
reject it as undefined), as is a variable defined twice or used without a definition. Every error is a
:class:`~glu.errors.GrammarError` giving the file, line and column.

The grammar that ships with glu (``glu/resources/grammar.grm``, :func:`load_grammar` with no argument) is
glu's own text of the originals' grammar: it generates the same sentences.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from glu.errors import GrammarError
from glu.paths import RESOURCES_DIR

DEFAULT_GRAMMAR_PATH: Path = RESOURCES_DIR / "grammar.grm"
"""glu's default grammar, equivalent to ``data/affordance-words/grammar.grm`` of the originals.

:meta hide-value:
"""

META = frozenset("{}[]<>|=$();\\/*")
"""HParse's meta characters: they end a word unless escaped with a backslash."""
MAX_NESTING = 100
"""Deepest bracket nesting accepted (deeper input raises GrammarError instead of exhausting the stack)."""

Pos = tuple[int, int]


# ---------------------------------------------------------------------------------------------- the tree
@dataclass(frozen=True)
class Node:
    """A node of the tree: ``pos`` is where it starts in the grammar's text, (line, column), for error
    messages (keyword-only; not compared or shown)."""

    pos: Pos = field(default=(0, 0), compare=False, repr=False, kw_only=True)


@dataclass(frozen=True)
class Word(Node):
    """A word of the sentence."""

    text: str


@dataclass(frozen=True)
class Ref(Node):
    """A reference to a variable, ``$name`` (``name`` without the dollar)."""

    name: str


@dataclass(frozen=True)
class Seq(Node):
    """Factors one after the other."""

    items: tuple[Expr, ...]


@dataclass(frozen=True)
class Alt(Node):
    """Alternatives, ``a | b | c``: exactly one of them."""

    options: tuple[Expr, ...]


@dataclass(frozen=True)
class Opt(Node):
    """An optional part, ``[ … ]``."""

    expr: Expr


@dataclass(frozen=True)
class Rep(Node):
    """A repetition: ``{ … }`` (``at_least_one=False``, zero or more) or ``< … >`` (one or more)."""

    expr: Expr
    at_least_one: bool = False


Expr = Word | Ref | Seq | Alt | Opt | Rep


def format_expr(expr: Expr) -> str:
    """The HParse text of an expression (words escaped where needed)."""
    if isinstance(expr, Word):
        return "".join("\\" + c if c in META or c == "%" else c for c in expr.text)
    if isinstance(expr, Ref):
        return "$" + expr.name
    if isinstance(expr, Seq):
        return " ".join(f"({format_expr(e)})" if isinstance(e, Alt) else format_expr(e) for e in expr.items)
    if isinstance(expr, Alt):
        return " | ".join(format_expr(e) for e in expr.options)
    if isinstance(expr, Opt):
        return f"[{format_expr(expr.expr)}]"
    return f"< {format_expr(expr.expr)} >" if expr.at_least_one else f"{{{format_expr(expr.expr)}}}"  # Rep


def children(expr: Expr) -> tuple[Expr, ...]:
    """The direct sub-expressions of ``expr`` (none for a word or a variable; variables are not followed)."""
    if isinstance(expr, Seq):
        return expr.items
    if isinstance(expr, Alt):
        return expr.options
    if isinstance(expr, Opt | Rep):
        return (expr.expr,)
    return ()


def walk(expr: Expr) -> Iterator[Expr]:
    """Every sub-expression of ``expr`` (itself first), without following variables."""
    stack = [expr]
    while stack:
        e = stack.pop()
        yield e
        stack.extend(reversed(children(e)))


@dataclass(frozen=True)
class Grammar:
    """A parsed grammar: variable definitions and the sentence expression.

    Attributes
    ----------
    definitions : variable name (without ``$``) → its expression, in file order
    sentence : the expression of a whole sentence (the final ``( … )``)
    source : where the text came from (a path or ``"<string>"``)
    """

    definitions: Mapping[str, Expr]
    sentence: Expr
    source: str = "<string>"

    def expressions(self) -> Iterator[Expr]:
        """Every sub-expression the sentence uses, following each variable it refers to once."""
        seen: set[str] = set()
        todo = [self.sentence]
        while todo:
            for e in walk(todo.pop()):
                yield e
                if isinstance(e, Ref) and e.name not in seen:
                    seen.add(e.name)
                    todo.append(self.definitions[e.name])

    @property
    def vocabulary(self) -> tuple[str, ...]:
        """The words a sentence can contain, sorted (variables unused by the sentence do not count)."""
        return tuple(sorted({e.text for e in self.expressions() if isinstance(e, Word)}))

    @property
    def has_repetition(self) -> bool:
        """True when the sentence uses ``{ }`` or ``< >`` (its language may then be infinite)."""
        return any(isinstance(e, Rep) for e in self.expressions())

    def format(self) -> str:
        """The grammar as HParse text (comments and layout are not kept)."""
        lines = [f"${name} = {format_expr(expr)};" for name, expr in self.definitions.items()]
        lines.append(f"({format_expr(self.sentence)})")
        return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------------------------- the lexer
@dataclass(frozen=True)
class _Token:
    kind: str  # "word", "var", "eof", or the punctuation itself: ( ) [ ] { } < > | = ;
    text: str
    line: int
    col: int

    def describe(self) -> str:
        shown = {"eof": "the end of the grammar", "word": f"the word {self.text!r}", "var": f"${self.text}"}
        return shown.get(self.kind, f"'{self.text}'")


_PUNCT = frozenset("()[]{}<>|=;")


def _tokenize(text: str, source: str) -> list[_Token]:
    tokens: list[_Token] = []
    i, line, col, n = 0, 1, 1, len(text)

    def err(msg: str, ln: int, cl: int) -> GrammarError:
        return GrammarError(msg, source, ln, cl)

    def advance(k: int) -> None:
        nonlocal i, line, col
        for _ in range(k):
            if text[i] == "\n":
                line, col = line + 1, 1
            else:
                col += 1
            i += 1

    def read_name(start_line: int, start_col: int, what: str) -> str:
        """Read a word or variable name: chars up to whitespace or an unescaped meta character."""
        chars: list[str] = []
        internal: str | None = None
        while i < n:
            c = text[i]
            if c == "\\":
                if i + 1 >= n:
                    raise err("a backslash at the end of the grammar escapes nothing", line, col)
                advance(1)
                chars.append(text[i])
                advance(1)
                continue
            if c.isspace() or c in META:
                break
            if c == "%" and internal is None:
                internal = "".join(chars)
                if not internal:
                    raise err(f"{what} cannot start with '%' (HParse's external-name separator)", line, col)
            chars.append(c)
            advance(1)
        return internal if internal is not None else "".join(chars)

    while i < n:
        c = text[i]
        if c.isspace():
            advance(1)
            continue
        ln, cl = line, col
        if c == "/":
            if text.startswith("/*", i):
                end = text.find("*/", i + 2)
                if end < 0:
                    raise err("comment '/*' is never closed with '*/'", ln, cl)
                advance(end + 2 - i)
                continue
            raise err(
                "unexpected '/': comments are written /* … */ (escape a literal slash as '\\/')", ln, cl
            )
        if c == "*":
            raise err("unexpected '*' outside a comment (escape a literal star as '\\*')", ln, cl)
        if c == "$":
            advance(1)
            name = read_name(ln, cl, "a variable name")
            if not name:
                raise err("'$' must be followed by a variable name, e.g. $object", ln, cl)
            tokens.append(_Token("var", name, ln, cl))
            continue
        if c in _PUNCT:
            if c in "<>" and text.startswith(c * 2, i):
                raise err(f"'{c * 2}' (HParse context-dependent loops) is not supported", ln, cl)
            advance(1)
            tokens.append(_Token(c, c, ln, cl))
            continue
        word = read_name(ln, cl, "a word")
        if not word:  # pragma: no cover - every non-meta, non-space char starts a non-empty name
            raise err(f"unexpected character {c!r}", ln, cl)
        tokens.append(_Token("word", word, ln, cl))
    tokens.append(_Token("eof", "", line, col))
    return tokens


# -------------------------------------------------------------------------------------------- the parser
_CLOSE = {"(": ")", "[": "]", "{": "}", "<": ">"}
_FACTOR_START = frozenset({"word", "var", "(", "[", "{", "<"})


class _Parser:
    def __init__(self, tokens: list[_Token], source: str) -> None:
        self.tokens, self.source, self.k, self.depth = tokens, source, 0, 0

    @property
    def tok(self) -> _Token:
        return self.tokens[self.k]

    def error(self, msg: str, tok: _Token | None = None) -> GrammarError:
        tok = tok or self.tok
        return GrammarError(msg, self.source, tok.line, tok.col)

    def expect(self, kind: str, context: str) -> _Token:
        tok = self.tok
        if tok.kind != kind:
            raise self.error(f"expected '{kind}' {context}, found {tok.describe()}")
        self.k += 1
        return tok

    def network(self) -> tuple[dict[str, Expr], dict[str, Pos], Expr]:
        defs: dict[str, Expr] = {}
        def_pos: dict[str, Pos] = {}
        while self.tok.kind == "var":
            var = self.tok
            self.k += 1
            if var.text in defs:
                first = def_pos[var.text]
                raise self.error(
                    f"${var.text} is defined twice (first at line {first[0]}, column {first[1]})", var
                )
            self.expect("=", f"after ${var.text} (a definition is '${var.text} = …;')")
            expr = self.expr()
            prev = self.tokens[self.k - 1]
            if self.tok.kind == "=" and prev.kind == "var":  # "$a = x  $b = y;": the ';' was forgotten
                raise self.error(
                    f"expected ';' at the end of the definition of ${var.text} (line {var.line}), "
                    f"before the definition of ${prev.text}",
                    prev,
                )
            self.expect(";", f"at the end of the definition of ${var.text} (line {var.line})")
            defs[var.text] = expr
            def_pos[var.text] = (var.line, var.col)
        if self.tok.kind != "(":
            what = "a definition '$name = …;' or the sentence '( … )'"
            if self.tok.kind == "eof":
                raise self.error(
                    f"the grammar has no sentence: expected {what}, found the end of the grammar"
                )
            raise self.error(f"expected {what}, found {self.tok.describe()}")
        open_tok = self.tok
        self.k += 1
        sentence = self.expr()
        if self.tok.kind != ")":
            raise self.error(
                f"expected ')' closing the sentence opened at line {open_tok.line}, "
                f"column {open_tok.col}, found {self.tok.describe()}"
            )
        self.k += 1
        if self.tok.kind != "eof":
            raise self.error(f"nothing may follow the sentence '( … )', found {self.tok.describe()}")
        return defs, def_pos, sentence

    def expr(self) -> Expr:
        first = self.tok
        options = [self.sequence()]
        while self.tok.kind == "|":
            self.k += 1
            options.append(self.sequence())
        return options[0] if len(options) == 1 else Alt(tuple(options), pos=(first.line, first.col))

    def sequence(self) -> Expr:
        first = self.tok
        if first.kind not in _FACTOR_START:
            raise self.error(f"expected a word, a $variable or an opening bracket, found {first.describe()}")
        items = []
        while self.tok.kind in _FACTOR_START:
            items.append(self.factor())
        return items[0] if len(items) == 1 else Seq(tuple(items), pos=(first.line, first.col))

    def factor(self) -> Expr:
        tok = self.tok
        pos = (tok.line, tok.col)
        self.k += 1
        if tok.kind == "word":
            return Word(tok.text, pos=pos)
        if tok.kind == "var":
            return Ref(tok.text, pos=pos)
        self.depth += 1
        if self.depth > MAX_NESTING:
            raise self.error(f"brackets are nested more than {MAX_NESTING} deep", tok)
        inner = self.expr()
        close = _CLOSE[tok.kind]
        if self.tok.kind != close:
            raise self.error(
                f"expected '{close}' closing the '{tok.kind}' at line {tok.line}, column {tok.col}, "
                f"found {self.tok.describe()}"
            )
        self.k += 1
        self.depth -= 1
        if tok.kind == "(":
            return inner
        if tok.kind == "[":
            return Opt(inner, pos=pos)
        return Rep(inner, tok.kind == "<", pos=pos)


def _check_references(defs: Mapping[str, Expr], sentence: Expr, source: str) -> None:
    """Raise GrammarError for an undefined variable or a recursive definition."""
    refs: dict[str, list[Ref]] = {}
    for name, expr in [*defs.items(), ("", sentence)]:
        refs[name] = [e for e in walk(expr) if isinstance(e, Ref)]
        for r in refs[name]:
            if r.name not in defs:
                close = difflib.get_close_matches(r.name, list(defs), n=1)
                hint = f" (did you mean ${close[0]}?)" if close else ""
                known = ", ".join("$" + d for d in defs) or "none"
                raise GrammarError(
                    f"${r.name} is not defined{hint}; defined variables: {known}", source, *r.pos
                )
    # depth-first search for a cycle, iteratively (no recursion limit); colours: 1 on the path, 2 done
    colour: dict[str, int] = {}
    for root in defs:
        if colour.get(root):
            continue
        path: list[tuple[str, Ref | None]] = [(root, None)]
        iters = [iter(refs[root])]
        colour[root] = 1
        while iters:
            r = next(iters[-1], None)
            if r is None:
                colour[path[-1][0]] = 2
                path.pop()
                iters.pop()
                continue
            c = colour.get(r.name, 0)
            if c == 1:
                names = [p for p, _ in path]
                cycle = names[names.index(r.name) :] + [r.name]
                chain = " → ".join("$" + x for x in cycle)
                raise GrammarError(
                    f"recursive definition {chain}: a variable cannot refer to itself", source, *r.pos
                )
            if c == 0:
                colour[r.name] = 1
                path.append((r.name, r))
                iters.append(iter(refs[r.name]))


def parse_grammar(text: str, source: str = "<string>") -> Grammar:
    """Parse a grammar in HTK HParse syntax; raises :class:`GrammarError` (with line, column) when
    malformed."""
    if not isinstance(text, str):
        raise GrammarError(f"a grammar is text, not {type(text).__name__}", source)
    parser = _Parser(_tokenize(text, source), source)
    defs, _, sentence = parser.network()
    _check_references(defs, sentence, source)
    return Grammar(definitions=defs, sentence=sentence, source=source)


def load_grammar(path: str | Path | None = None) -> Grammar:
    """Read and parse a grammar file; with no path, glu's default grammar (the originals' language)."""
    p = DEFAULT_GRAMMAR_PATH if path is None else Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise GrammarError("no such grammar file", str(p)) from None
    except IsADirectoryError:
        raise GrammarError("is a folder, not a grammar file", str(p)) from None
    except UnicodeDecodeError as e:
        raise GrammarError(f"not UTF-8 text ({e.reason} at byte {e.start})", str(p)) from None
    except OSError as e:
        raise GrammarError(f"cannot read the grammar file ({e.strerror})", str(p)) from None
    return parse_grammar(text, "glu default grammar" if path is None else str(p))
