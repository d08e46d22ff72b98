"""The site's API reference: one page per public module of the package, found by walking it, and every
cross-reference to a glu name linked.

:func:`api_modules` walks the package's files (every module and package whose dotted name has no part
starting with ``_``; the notebooks and resources it ships are not Python API) and orders them as
:data:`glu.LAYERS` reads, bottom first: a module added to glu gets its page without anyone listing it.
:func:`api_pages` writes the reStructuredText of the reference: the API page (the components layer by
layer, each with the first line of its docstring) and one page per module (autodoc, from the numpydoc
docstrings). A package's page shows its own docstring, the public names it gathers from its modules
(linked to where each is documented) and its modules; a name it gathers from a private module is
documented on the package's page itself.

As a Sphinx extension (the site's configuration lists this module), :func:`resolve_reference` links the
references Sphinx cannot: a name re-exported by a package (``glu.bn.BayesNet``), a short name written in a
module's docstring (``:class:`Recognizer```), a type hint. It imports the name from the module where the
reference is written (and the packages above it) and links it to the page that documents that object. A
reference to a public glu name that leads nowhere is a warning, so it fails the build (every warning
does); names outside glu (numpy, pandas) stay plain text, as the site is built offline.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import glu
from glu import paths

NOT_API = ("resources", "notebooks")
"""Folders of the package that hold no Python API (the site's files, the shipped notebooks)."""


def _public(name: str) -> bool:
    return not any(part.startswith("_") for part in name.split("."))


def _walk(package_dir: Path) -> Iterator[str]:
    for f in sorted(package_dir.rglob("*.py")):
        rel = f.relative_to(package_dir.parent).with_suffix("").parts
        if rel[1:2] and rel[1] in NOT_API:
            continue
        name = ".".join(rel[:-1] if rel[-1] == "__init__" else rel)
        if _public(name):
            yield name


def _component(module: str) -> tuple[int, int]:
    """(layer, position in it) of the longest component of :data:`glu.LAYERS` holding ``module``."""
    best, key = "", (len(glu.LAYERS), 0)
    for i, layer in enumerate(glu.LAYERS):
        for j, c in enumerate(layer):
            if (module == c or module.startswith(c + ".")) and len(c) > len(best):
                best, key = c, (i, j)
    return key


def api_modules(package_dir: Path = paths.PACKAGE_DIR) -> tuple[str, ...]:
    """Every public module of the package in reading order: by the layer of :data:`glu.LAYERS` it belongs
    to (bottom first), its component's place in that layer, then a package before its modules, by name."""
    return tuple(sorted(_walk(package_dir), key=_reading_order))


def _reading_order(module: str) -> tuple[Any, ...]:
    return (*_component(module), module.split("."))


def _title(text: str) -> str:
    return f"{text}\n{'=' * len(text)}\n"


def _autosummary(names: list[str]) -> list[str]:
    return [".. autosummary::", "", *(f"   {n}" for n in names), ""] if names else []


def _gathered(package: str) -> tuple[list[str], list[tuple[str, str]]]:
    """A package's public names defined in its modules: (those documented on their module's page, those
    from a private module, as (name, autodoc directive), which the package's page documents itself)."""
    mod = importlib.import_module(package)
    names = getattr(mod, "__all__", None) or [n for n in vars(mod) if not n.startswith("_")]
    linked, own = [], []
    for name in names:
        obj = getattr(mod, name, None)
        home = getattr(obj, "__module__", None)
        if inspect.ismodule(obj) or home is None or home == package or not home.startswith("glu"):
            continue  # a submodule (listed below), data (documented where defined), or the package's own
        if _public(home):
            linked.append(name)
        else:
            own.append((name, "autoclass" if inspect.isclass(obj) else "autofunction"))
    return linked, own


def module_page(module: str, modules: tuple[str, ...]) -> str:
    """The reStructuredText page of one module (or package) of the API reference."""
    lines = [_title(module)]
    if hasattr(importlib.import_module(module), "__path__"):  # a package
        lines += [f".. automodule:: {module}", "   :members:", "   :ignore-module-all:", ""]
        linked, own = _gathered(module)
        if linked or own:
            lines += ["Public names", "------------", "", *_autosummary(linked + [n for n, _ in own])]
        children = [m for m in modules if m.rpartition(".")[0] == module]
        below = [m for m in children if m not in _tops(modules)]  # the others are on the API page
        if children:
            lines += ["Modules", "-------", "", *_autosummary([m[len(module) + 1 :] for m in children])]
        if below:
            lines += [".. toctree::", "   :hidden:", "", *(f"   {m}" for m in below), ""]
        for name, kind in own:
            lines += [f".. {kind}:: {module}.{name}", ""]
    else:
        lines += [f".. automodule:: {module}", ""]  # its docstring, then its members (the page's contents)
    return "\n".join(lines)


def _tops(modules: tuple[str, ...]) -> list[str]:
    """The modules the API page lists: the components of :data:`glu.LAYERS`, and any module whose package
    is not documented; the others are reached from their package's page."""
    components = {c for layer in glu.LAYERS for c in layer}
    return [m for m in modules if m in components or m.rpartition(".")[0] not in modules]


def _sections(modules: tuple[str, ...]) -> list[tuple[str, list[str]]]:
    """The API page's sections: the library, the studies, then the runner and the command line."""
    tops = _tops(modules)
    studies = [m for m in tops if m == "glu.studies" or m.startswith("glu.studies.")]
    runner = [m for m in tops if m.split(".")[:2] in (["glu", "run"], ["glu", "cli"])]
    library = [m for m in tops if m not in studies and m not in runner]
    return [
        ("The library", library),
        ("The studies", studies),
        ("The notebook runner and the command line", runner),
    ]


API_INTRO = """\
Every public module of glu, generated from its docstrings (numpydoc style), layer by layer as
:data:`glu.LAYERS` stacks them: the library first, each module importing only from those above it on this
page, then the studies, then the notebook runner and the command line (``glu --help``), which are built on
them. A package's page lists the names it gathers and its modules."""


def api_index(modules: tuple[str, ...]) -> str:
    """The API page: the components of each section with the first line of their docstring, and the
    toctree of their pages (``api/<module>``)."""
    lines = [_title("API reference"), API_INTRO, ""]
    listed: list[str] = []
    for title, names in _sections(modules):
        lines += [title, "-" * len(title), "", *_autosummary(names)]
        listed += names
    lines += [".. toctree::", "   :hidden:", "", *(f"   api/{m}" for m in listed), ""]
    return "\n".join(lines)


def api_pages(modules: tuple[str, ...]) -> dict[str, str]:
    """Every page of the API reference: ``api.rst`` and ``api/<module>.rst``, as path → text."""
    modules = tuple(sorted(modules, key=_reading_order))
    pages = {"api.rst": api_index(modules)}
    for m in modules:
        pages[f"api/{m}.rst"] = module_page(m, modules)
    return pages


# ------------------------------------------------------------------------------------------ references
def _resolve_path(dotted: str) -> tuple[Any, bool]:
    """The object a dotted glu path names (importing the longest module prefix), and whether it exists."""
    try:
        return pkgutil.resolve_name(dotted), True
    except (ImportError, AttributeError, ValueError):
        return None, False


def _candidates(target: str, module: str, cls: str | None) -> list[str]:
    """The glu paths a reference written in ``module`` (inside class ``cls``) may mean, nearest first."""
    if target.startswith("glu.") or target == "glu":
        return [target]
    scopes = [module.rsplit(".", k)[0] for k in range(module.count(".") + 1)] if module else []
    out = [f"{s}.{cls}.{target}" for s in scopes[:1] if cls] + [f"{s}.{target}" for s in scopes]
    return [c for c in out if c.startswith("glu.")]


def _canonical(obj: Any, path: str) -> str:
    """Where ``obj`` is defined (``glu.bn.model.BayesNet`` for ``glu.bn.BayesNet``); its path for data."""
    if inspect.ismodule(obj):
        return obj.__name__
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if isinstance(module, str) and isinstance(qualname, str) and "<" not in qualname:
        return f"{module}.{qualname}"
    return path


def _in_api(name: str) -> bool:
    """Whether a dotted name is glu's public API: no part private, and in its module's ``__all__`` when that
    module has one."""
    if not (name == "glu" or name.startswith("glu.")) or not _public(name):
        return False
    parent, _, last = name.rpartition(".")
    module, found = _resolve_path(parent)
    return not (found and inspect.ismodule(module) and last not in getattr(module, "__all__", [last]))


def _is_documented_here(name: str, modules: tuple[str, ...] | None) -> bool:
    """Whether the module ``name`` belongs to (the longest prefix that is a module) is among the
    ``modules`` this build documents (None: all)."""
    parts = name.split(".")
    home = next(
        (".".join(parts[:k]) for k in range(len(parts), 0, -1) if ".".join(parts[:k]) in sys.modules), ""
    )
    return modules is None or home in modules


def _documented(py: Any, obj: Any, canonical: str) -> str | None:
    """The documented name of ``obj``: its canonical name, or a documented name bound to the same object
    (data re-exported by a package)."""
    if canonical in py.objects:
        return canonical
    last = canonical.rpartition(".")[2]
    for name in py.objects:
        if name.rpartition(".")[2] == last and _resolve_path(name)[0] is obj:
            return name
    return None


def resolve_reference(app: Any, env: Any, node: Any, contnode: Any) -> Any:
    """Sphinx's ``missing-reference``: link a reference to a glu name the Python domain did not find (see
    the module docstring); warn when a public glu name leads to no page."""
    from sphinx.util import logging

    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"].lstrip("~.")
    for path in _candidates(target, node.get("py:module") or "", node.get("py:class")):
        obj, found = _resolve_path(path)
        if not found:
            continue
        canonical = _canonical(obj, path)
        if not _in_api(canonical):
            return None  # a name from outside glu, a private one, or one its module keeps out of __all__
        py = env.get_domain("py")
        name = _documented(py, obj, canonical)
        if name is None:
            target = canonical
            break
        return py.resolve_xref(env, node["refdoc"], app.builder, "obj", name, node, contnode)
    else:
        if not _in_api(target):
            return None
    if not _is_documented_here(target, app.config.glu_api_modules):
        return None  # a build of part of the reference (the tests'): only its own modules must link
    logging.getLogger(__name__).warning(
        "the reference to %s leads to no page of the API reference", target, location=node
    )
    return None


def _shape_words() -> Any:
    """A post-transform that leaves unlinked the words of a parameter's type that name no class. glu's
    docstrings write a parameter's description where numpydoc puts its type (``n_frames : the number of
    frames``) and give shapes there (``array, shape (n_frames, 3)``); Sphinx would link each such word to
    any attribute of that name anywhere, and warn when it finds several."""
    from sphinx import addnodes
    from sphinx.transforms.post_transforms import SphinxPostTransform

    class ShapeWords(SphinxPostTransform):
        default_priority = 5  # before Sphinx resolves the references (10)

        def run(self, **kwargs: Any) -> None:
            py = self.env.get_domain("py")
            for node in list(self.document.findall(addnodes.pending_xref)):
                if node.get("refdomain") != "py" or not node.get("refspecific"):
                    continue
                args = (self.env, node.get("py:module"), node.get("py:class"), node["reftarget"])
                if "." not in node["reftarget"] and len(py.find_obj(*args, "class", 1)) != 1:
                    node.replace_self(node.children)

    return ShapeWords


def setup(app: Any) -> dict[str, Any]:
    """The Sphinx extension: :func:`resolve_reference` on ``missing-reference``, and the words of shapes
    in parameter types left unlinked."""
    app.add_config_value("glu_api_modules", None, "env")  # the modules documented, when not all of them
    app.connect("missing-reference", resolve_reference)
    app.add_post_transform(_shape_words())
    return {"parallel_read_safe": True, "parallel_write_safe": True}
