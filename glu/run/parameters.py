"""Notebook parameters: declared once in each notebook's parameters cell, checked before anything runs.

Every notebook (``notebooks/NN_name.py``) declares its parameters in its one cell tagged ``parameters``,
one per line, as papermill and ``papermill --help-notebook`` read them::

    rule: str = "virtual"  # how p_HMM enters the network: "virtual" (the originals') or "jeffrey"

:func:`read_spec` reads that declaration (name, type, default, comment) from the notebook's source, and
:func:`check` checks a set of values against it:

* **names** — only declared names (a near miss gets a suggestion);
* **types** — ``bool`` is ``True`` or ``False`` (not ``"no"``), ``int`` an integer, ``float`` a finite
  number, ``str`` a string, ``list[float]`` a list of numbers; ``None`` only where the default is None;
* **choices and ranges** — :func:`choices` and :data:`RANGES`, keyed by parameter name: a name means the
  same thing in every notebook, and the allowed values come from the package's own constants (the
  library's in :data:`CHOICES`, each study's from its package: :func:`glu.studies.parameter_choices`).

``glu run`` checks before it starts a kernel; :func:`glu.run.notebook.start`, the first call of every
notebook, checks again inside the kernel, so a plain papermill run is checked too.
"""

from __future__ import annotations

import ast
import difflib
import functools
import io
import itertools
import math
import re
import tokenize
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from glu.bn.learning import UNSEEN_MODES
from glu.bn.soft import SOFT_RULES
from glu.data.source import WORD_FILES
from glu.errors import ParameterError
from glu.gestures.calibration import READINGS
from glu.gestures.invariants import FEATURE_NAMES
from glu.language.descriptions import SCORES
from glu.schema import AFFORDANCE_VALUES

CHOICES: dict[str, tuple[str, ...]] = {
    "words": tuple(WORD_FILES),
    "unseen_words": UNSEEN_MODES,
    "rule": SOFT_RULES,
    "score": tuple(SCORES),
    "shape": AFFORDANCE_VALUES["Shape"],
    "size": AFFORDANCE_VALUES["Size"],
    "features": FEATURE_NAMES,
    "real_features": FEATURE_NAMES,
    "p_hmm": tuple(READINGS),
}
"""Allowed values of the library's string parameters that take one of a few values (for a list, of each
element); :func:`choices` adds the studies' own."""


@functools.cache
def choices() -> dict[str, tuple[str, ...]]:
    """Allowed values of every string parameter that takes one of a few: :data:`CHOICES` and the studies'."""
    from glu.studies import parameter_choices

    return {**CHOICES, **parameter_choices()}


RANGES: dict[str, tuple[float, float]] = {
    "seed": (0, 2**32 - 1),
    "n_states": (1, 50),
    "n_mix": (1, 20),
    "n_per_action": (2, 100_000),
    "folds": (2, 1000),
    "noise_levels": (0.0, 1.0),
    "eval_tol": (1e-12, 1.0),
    "threshold": (0.0, 1.0),
    "step": (1, 100_000),
    "n_points": (2, 1_000_001),
    "nbest": (1, 100_000),
    "n_samples": (1, 1_000_000),
    "n_trials": (1, 100_000),
    "episodes": (1, 100_000_000),
    "fractions": (1e-9, 1.0),
    "bootstrap": (0, 10_000),
    "workers": (0, 1024),
    "seeds": (0, 2**32 - 1),
    "real_seeds": (0, 2**32 - 1),
    "view_gesture": (0, 2**32 - 1),
    "n_train": (1, 100_000),
    "n_test": (1, 100_000),
    "n_iter": (1, 100_000),
    "chunk_size": (1, 10_000_000),
    "recognizer_seeds": (1, 1000),
    "calibration_per_action": (1, 100_000),
    "learn_experiments": (10, 10_000_000),
    "yaws": (-360.0, 360.0),
    "variety": (0.0, 3.0),
}
"""Inclusive ranges of the numeric parameters (for a list, of each element)."""

PLUMBING: tuple[str, ...] = ("data", "out_dir")
"""Parameters that say where things are, not what is computed: never listed among a run's parameters."""

TYPES = ("str", "int", "float", "bool", "list[float]", "list[int]", "list[str]")
"""The types a notebook's parameter may be declared with."""
_CELL = re.compile(r'^# %%.*tags=\["parameters"\]')


@dataclass(frozen=True)
class Parameter:
    """One declared parameter: ``name: type = default  # help``."""

    name: str
    type: str
    default: Any
    help: str

    @property
    def choices(self) -> tuple[str, ...] | None:
        """The allowed values, if the parameter takes one of a few."""
        return choices().get(self.name)

    @property
    def range(self) -> tuple[float, float] | None:
        """The inclusive range of a numeric parameter (of each element, for a list), if it has one."""
        return RANGES.get(self.name)

    def describe(self) -> str:
        """``name: type = default  [allowed]  help`` (for ``glu run --list``)."""
        allowed = (
            f"  {{{', '.join(self.choices)}}}"
            if self.choices
            else f"  [{_num(self.range[0])}, {_num(self.range[1])}]"
            if self.range
            else ""
        )
        return f"{self.name}: {self.type} = {self.default!r}{allowed}  # {self.help}"


def read_spec(path: str | Path) -> dict[str, Parameter]:
    """The parameters declared in the ``parameters`` cell of a jupytext percent notebook, in order.

    Raises :class:`ParameterError` when the notebook has no such cell, or a line of it is not
    ``name: type = literal  # comment`` with a type of :data:`TYPES`.
    """
    path = Path(path)
    lines = path.read_text(encoding="utf-8").splitlines()
    starts = [i for i, line in enumerate(lines) if _CELL.match(line)]
    if len(starts) != 1:
        raise ParameterError(f"{path.name}: expected one cell tagged parameters, found {len(starts)}")
    body = itertools.takewhile(lambda line: not line.startswith("# %%"), lines[starts[0] + 1 :])
    text = "\n".join(body) + "\n"
    comments = {
        tok.start[0]: tok.string.lstrip("#").strip()
        for tok in tokenize.generate_tokens(io.StringIO(text).readline)
        if tok.type == tokenize.COMMENT
    }
    spec: dict[str, Parameter] = {}
    for node in ast.parse(text).body:
        where = f"{path.name}, parameters cell line {node.lineno}"
        if not (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value):
            raise ParameterError(f"{where}: expected `name: type = value  # comment`")
        kind = ast.unparse(node.annotation)
        if kind not in TYPES:
            raise ParameterError(f"{where}: type {kind!r} is not one of {', '.join(TYPES)}")
        try:
            default = ast.literal_eval(node.value)
        except ValueError:
            raise ParameterError(f"{where}: the default of {node.target.id} is not a literal") from None
        help_text = comments.get(node.end_lineno) or comments.get(node.lineno) or ""
        spec[node.target.id] = Parameter(node.target.id, kind, default, help_text)
    return spec


def _num(x: float) -> str:
    return str(int(x)) if float(x).is_integer() else f"{x:g}"


def _check_one(p: Parameter, value: Any, who: str) -> Any:
    def wrong(must: str, every: bool = False, sep: str = ",") -> ParameterError:
        return ParameterError(
            f"{who}: {'every element of ' if every else ''}{p.name} must be {must}{sep} got {value!r}"
        )

    if value is None:
        if p.default is None:
            return None
        raise wrong(f"a {p.type}")
    if p.type == "bool":
        if not isinstance(value, bool):
            raise wrong("True or False")
        return value
    if p.type == "str":
        if not isinstance(value, str):
            raise wrong("a string")
        if p.choices and value not in p.choices:
            raise wrong(f"one of {', '.join(p.choices)}", sep=";")
        return value
    if p.type in ("int", "float"):
        items, scalar = [value], True
    elif isinstance(value, list | tuple):
        items, scalar = list(value), False
    else:
        raise wrong(f"a list ({p.type})")
    element = p.type.removeprefix("list[").removesuffix("]")
    for v in items:
        if element == "str":
            if not isinstance(v, str):
                raise wrong("a string", every=True)
            if p.choices and v not in p.choices:
                raise wrong(f"one of {', '.join(p.choices)}", every=True, sep=";")
            continue
        if element == "int" and not (isinstance(v, int) and not isinstance(v, bool)):
            raise wrong("an integer" if scalar else "integers")
        if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
            raise wrong("a finite number" if scalar else "finite numbers")
        if p.range and not p.range[0] <= v <= p.range[1]:
            raise wrong(f"in [{_num(p.range[0])}, {_num(p.range[1])}]")
    return value


def check(
    spec: Mapping[str, Parameter], values: Mapping[str, Any], notebook: str = "notebook"
) -> dict[str, Any]:
    """Check ``values`` (name → value; absent names keep their defaults) against ``spec``.

    Returns every parameter's value (defaults filled in). Raises :class:`ParameterError` with one line
    naming the notebook, the parameter, what it must be and what it got.
    """
    for name in values:
        if name not in spec:
            close = difflib.get_close_matches(name, list(spec), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ParameterError(
                f"{notebook}: unknown parameter {name!r}{hint}; its parameters are {', '.join(spec)}"
            )
    return {name: _check_one(p, values.get(name, p.default), notebook) for name, p in spec.items()}


def non_defaults(spec: Mapping[str, Parameter], values: Mapping[str, Any]) -> dict[str, Any]:
    """The values that differ from their defaults, in declaration order (:data:`PLUMBING` left out)."""
    return {
        n: values[n] for n, p in spec.items() if n in values and n not in PLUMBING and values[n] != p.default
    }


def parse_value(p: Parameter, text: str, notebook: str = "notebook") -> Any:
    """A command-line value for ``p`` (``glu run -p NAME VALUE``), parsed by the declared type, then checked.

    ``True``/``False`` (any case) for bool; a list as ``[0, 0.1]`` or ``0,0.1``; ``None`` where the
    default is None.
    """
    t = text.strip()
    who = f"{notebook}: -p {p.name} {text!r}"
    if t == "None" and p.default is None:
        return None
    if p.type == "bool":
        if t.lower() not in ("true", "false"):
            raise ParameterError(f"{who}: {p.name} must be True or False")
        return t.lower() == "true"
    if p.type == "str":
        return _check_one(p, text, notebook)
    if p.type.startswith("list["):
        parts = t.strip("[]").split(",") if t.strip("[]").strip() else []
        element = p.type.removeprefix("list[").removesuffix("]")
        value = [_scalar(element, x.strip().strip("'\""), who) for x in parts]
        return _check_one(p, value, notebook)
    return _check_one(p, _scalar(p.type, t, who), notebook)


def _scalar(kind: str, t: str, who: str) -> Any:
    if kind == "str":
        return t
    try:
        return int(t) if kind == "int" else float(t)
    except ValueError:
        raise ParameterError(f"{who}: not {'an integer' if kind == 'int' else 'a number'}") from None
