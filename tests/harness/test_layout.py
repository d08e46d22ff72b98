"""The package's layout stays true: imports only go downward, every module has a layer, none is too long.

The layers are :data:`glu.LAYERS`, bottom first (docs/api.md, "Package layout"). A module may import from a
lower layer and from its own component; never from a higher layer, and never from a sibling component of the
same layer (the network, the gestures and the language know nothing of each other; a study knows no other
study but the shared ones). No module imports a private (``_``) name, or a private module, of another module.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import glu

PACKAGE = Path(glu.__file__).resolve().parent

LAYERS = glu.LAYERS
LAYER = {component: i for i, layer in enumerate(LAYERS) for component in layer}
MAX_LINES = 800


def modules() -> dict[str, Path]:
    """Every module of the package: dotted name → file."""
    out = {}
    for f in sorted(PACKAGE.rglob("*.py")):
        parts = f.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = f
    return out


def component(module: str) -> str:
    """The longest entry of :data:`LAYERS` that is ``module`` or a package containing it."""
    best = ""
    for c in LAYER:
        if (module == c or module.startswith(c + ".")) and len(c) > len(best):
            best = c
    return best


def glu_imports(path: Path, name: str) -> list[tuple[int, str, tuple[str, ...] | None]]:
    """(line, module, names) for every import of a glu module in a file, including imports inside functions:
    names None for ``import glu.x``, else the names of ``from glu.x import …`` (relative imports resolved)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    is_package = path.name == "__init__.py"
    out: list[tuple[int, str, tuple[str, ...] | None]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name, None) for a in node.names if a.name.split(".")[0] == "glu"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".")
                base = base[: len(base) - node.level + (1 if is_package else 0)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if mod.split(".")[0] == "glu":
                out.append((node.lineno, mod, tuple(a.name for a in node.names)))
    return out


def imported_modules(path: Path, name: str) -> list[tuple[int, str]]:
    """(line, module) for every import of a glu module in a file, including imports inside functions."""
    out = []
    for line, mod, names in glu_imports(path, name):
        if names is None:
            out.append((line, mod))
        for a in names or ():  # `from glu import plots` imports the module glu.plots
            sub = f"{mod}.{a}"
            out.append((line, sub if component(sub) != component(mod) else mod))
    return out


def test_the_checker_sees_imports_inside_functions_and_relative_ones(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("def f():\n    from glu.plots import style\n    import glu.cli\nfrom . import errors\n")
    found = {m for _, m in imported_modules(f, "glu.m")}
    assert found == {"glu.plots", "glu.cli", "glu.errors"}


def test_every_module_has_a_layer():
    missing = [m for m in modules() if not component(m)]
    assert not missing, f"place these modules in LAYERS (glu/__init__.py and the README): {missing}"


def test_imports_only_go_downward():
    bad = []
    for name, path in modules().items():
        here = component(name)
        for line, target in imported_modules(path, name):
            there = component(target)
            if there == here:
                continue
            if not there:
                bad.append(f"{path.relative_to(PACKAGE.parent)}:{line}: {target} is not a glu module")
            elif LAYER[there] >= LAYER[here]:
                kind = "a sibling" if LAYER[there] == LAYER[here] else "a higher layer"
                bad.append(f"{path.relative_to(PACKAGE.parent)}:{line}: {here} imports {target} ({kind})")
    assert not bad, "imports that break the layering:\n" + "\n".join(bad)


@pytest.mark.parametrize("upward", ["from glu.cli import main", "import glu.run.reproduce"])
def test_an_upward_import_is_caught(tmp_path, upward):
    f = tmp_path / "inference.py"
    f.write_text(f"def f():\n    {upward}\n")
    (target,) = [m for _, m in imported_modules(f, "glu.bn.inference")]
    assert LAYER[component(target)] > LAYER[component("glu.bn.inference")]


def test_no_module_is_longer_than_800_lines():
    long = {m: n for m, p in modules().items() if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, f"split these modules (more than {MAX_LINES} lines): {long}"


def module_imports(path: Path, name: str, known: set[str]) -> set[str]:
    """The glu modules a file imports, at any depth of the file (functions included), each resolved to the
    module file it loads: ``from glu.hmm import em`` is ``glu.hmm.em``, ``from glu.hmm import train`` is
    the package face ``glu.hmm``."""

    def nearest(mod: str) -> str | None:
        while mod and mod not in known:
            mod = mod.rpartition(".")[0]
        return mod or None

    out = set()
    for _, mod, names in glu_imports(path, name):
        if names is None:
            out.add(nearest(mod))
        for a in names or ():
            out.add(f"{mod}.{a}" if f"{mod}.{a}" in known else nearest(mod))
    return {m for m in out if m and m != name}


def import_circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_circle_finder_sees_a_circle_through_a_function_level_import(tmp_path):
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("from glu.x import b\n")
    b.write_text("def f():\n    from glu.x.a import g\n")
    known = {"glu.x.a", "glu.x.b"}
    graph = {"glu.x.a": module_imports(a, "glu.x.a", known), "glu.x.b": module_imports(b, "glu.x.b", known)}
    assert import_circles(graph) == [["glu.x.a", "glu.x.b"]]
    assert import_circles({"glu.x.a": {"glu.x.b"}, "glu.x.b": set()}) == []


def test_no_import_circles_not_even_through_functions():
    mods = modules()
    known = set(mods)
    graph = {name: module_imports(path, name, known) for name, path in mods.items()}
    circles = import_circles(graph)
    assert not circles, "modules that import each other (directly or around a loop):\n" + "\n".join(
        " ↔ ".join(c) for c in circles
    )


MAX_FUNCTION_LINES = 80


def _private(part: str) -> bool:
    return part.startswith("_") and not (part.startswith("__") and part.endswith("__"))


def _is_module(dotted: str) -> bool:
    base = PACKAGE.parent / dotted.replace(".", "/")
    return base.with_suffix(".py").is_file() or (base / "__init__.py").is_file()


def private_imports(path: Path, name: str) -> list[tuple[int, str]]:
    """(line, what) for every private name (``_x``) this file imports from another module of glu, and every
    private module it imports from outside the package that holds it (``glu.hmm._engine`` is glu.hmm's
    own)."""
    out = []
    for line, mod, names in glu_imports(path, name):
        targets = [mod] if names is None else [f"{mod}.{a}" for a in names]
        for target in targets:
            parts = target.split(".")
            first = next((i for i, p in enumerate(parts) if _private(p)), None)
            if first is None:
                continue
            if first == len(parts) - 1 and not _is_module(target):  # a private name of module `mod`
                if mod != name:
                    out.append((line, target))
                continue
            owner = ".".join(parts[:first])  # a private module: its package's own
            if not (name == owner or name.startswith(owner + ".")):
                out.append((line, ".".join(parts[: first + 1])))
    return out


def test_the_private_checker_sees_a_private_name_taken_from_another_module(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("from glu.gestures._synthetic_batch import x\nfrom glu.hmm.em import _step\n")
    found = {w for _, w in private_imports(f, "glu.studies.learning.m")}
    assert found == {"glu.gestures._synthetic_batch", "glu.hmm.em._step"}
    assert private_imports(f, "glu.gestures.synthetic") == [(2, "glu.hmm.em._step")]
    g = tmp_path / "t.py"
    g.write_text("from glu.hmm._engine.batch import Bank\nfrom glu import __version__\n")
    assert private_imports(g, "glu.hmm.training") == []
    assert private_imports(g, "glu.studies.m") == [(1, "glu.hmm._engine")]


def test_no_private_name_crosses_modules():
    bad = [
        f"{path.relative_to(PACKAGE.parent)}:{line}: {what}"
        for name, path in modules().items()
        for line, what in private_imports(path, name)
    ]
    assert not bad, "private names imported from another module (make them public, or keep them home):\n" + (
        "\n".join(bad)
    )


def long_functions(path: Path) -> list[tuple[str, int]]:
    """(qualified name, lines) of every function or method of a file longer than the limit (its body from
    the ``def`` line to the last line, the docstring included)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    out = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                qual = f"{prefix}{child.name}"
                if not isinstance(child, ast.ClassDef):
                    n = child.end_lineno - child.lineno + 1
                    if n > MAX_FUNCTION_LINES:
                        out.append((qual, n))
                visit(child, qual + ".")

    visit(tree, "")
    return out


def test_no_function_is_longer_than_80_lines():
    long = {
        f"{path.relative_to(PACKAGE.parent)}::{qual}": n
        for path in modules().values()
        for qual, n in long_functions(path)
    }
    assert not long, f"split these functions at a seam (more than {MAX_FUNCTION_LINES} lines): {long}"
