"""The variables of an Affordance–Words model: node names, their values, their roles, and the words.

A **schema file** (JSON, or YAML with PyYAML) describes a network: the affordance nodes in K2 order, each
with its values, its role (``action``, ``object`` — a feature of the object — or ``effect``), and whether
the experimenter sets it (such nodes never get parents); then the word vocabulary (one binary node per
word, values ``absent`` and ``present``)::

    format: glu-schema
    version: 1
    name: tool use
    nodes:
      - {name: Tool, values: [stick, hook, rake], role: action, set_by_experimenter: true}
      - {name: ObjShape, values: [ball, cube], role: object, set_by_experimenter: true}
      - {name: Displacement, values: [none, small, large], role: effect}
    words: [the, robot, pulls, pushes, ball, cube, ...]
    aliases: {ObjShape: {sphere: ball}}          # optional: other names accepted on input

:func:`read_schema_file` reads one; :func:`default_schema` is GLU's own, the file
``glu/resources/schemas/glu.json``, from which this module's constants are taken. Value order is the order
of the original data files (docs/method.md §1.1) and is used everywhere: CPT axes, posterior vectors,
categorical columns. In glu the Shape value ``circle`` of the files is called ``sphere`` (the papers' name);
``circle`` is accepted as an alias on input. A word node takes the values ``absent`` and ``present`` (the
files' ``-`` and the word itself).

>>> s = read_schema_file(GLU_SCHEMA_FILE)
>>> s.affordance_nodes[:3], s.root_nodes, len(s.word_nodes), s.roles["ObjVel"]
(('Action', 'Color', 'Shape'), ('Action', 'Color', 'Shape', 'Size'), 49, 'effect')
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from glu.errors import DataError, UnknownNodeError, UnknownValueError
from glu.files import read_text
from glu.paths import RESOURCES_DIR

SCHEMA_FORMAT = "glu-schema"
SCHEMA_VERSION = 1
ROLES: tuple[str, ...] = ("action", "object", "effect")
"""What an affordance node is: the robot's action, a feature of the object, or an effect of the action."""
WORD_VALUES: tuple[str, str] = ("absent", "present")
GLU_SCHEMA_FILE: Path = RESOURCES_DIR / "schemas" / "glu.json"
"""GLU's schema: the 8 affordance nodes of the papers and their 49 words.

:meta hide-value:
"""


_GLU: dict[str, Any] = json.loads(GLU_SCHEMA_FILE.read_text(encoding="utf-8"))
AFFORDANCE_VALUES: dict[str, tuple[str, ...]] = {n["name"]: tuple(n["values"]) for n in _GLU["nodes"]}
"""Affordance nodes in the fixed K2 order, with their values in file order (glu names)."""
AFFORDANCE_NODES: tuple[str, ...] = tuple(AFFORDANCE_VALUES)
AFFORDANCE_ROLES: dict[str, str] = {n["name"]: n["role"] for n in _GLU["nodes"]}
"""GLU's affordance nodes → their roles (action, object, effect)."""
ACTIONS: tuple[str, ...] = AFFORDANCE_VALUES["Action"]
"""The actions, in the network's order: grasp, tap, touch (every p_HMM vector follows it)."""
ROOT_NODES: tuple[str, ...] = tuple(n["name"] for n in _GLU["nodes"] if n.get("set_by_experimenter"))
"""Set by the experimenter: they never get parents."""
WORDS: tuple[str, ...] = tuple(_GLU["words"])
"""The 49 words of the vocabulary, in file order."""
ACTION_VERBS: dict[str, tuple[str, ...]] = {
    "grasp": ("grasps", "grasping", "grasped", "picks", "picking", "picked"),
    "tap": ("taps", "tapping", "tapped", "pushes", "pushing", "pushed"),
    "touch": ("touches", "touching", "touched", "pokes", "poking", "poked"),
}
"""GLU's actions → the words of :data:`WORDS` that name them: two verbs each (tap and push, touch and poke,
as in the data), each as third person, ``-ing`` form and past participle."""
FILE_ALIASES: dict[str, dict[str, str]] = {k: dict(v) for k, v in _GLU.get("aliases", {}).items()}
"""Values as written in the original files → glu values."""


@dataclass(frozen=True)
class Schema:
    """Nodes of a model and their values: affordance nodes first (in K2 order), then word nodes.

    Attributes
    ----------
    values : mapping node → tuple of values, in order (affordance nodes first, then words)
    n_affordance : how many of the leading nodes are affordance nodes
    aliases : mapping node → {alias: value}, accepted on input
    roots : the nodes set by the experimenter (None: GLU's, Action, Color, Shape, Size, where present)
    roles : affordance node → ``action``, ``object`` or ``effect`` (where known)
    name : what the schema describes
    """

    values: Mapping[str, tuple[str, ...]]
    n_affordance: int
    aliases: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    roots: tuple[str, ...] | None = field(default=None, compare=False)
    roles: Mapping[str, str] = field(default_factory=dict, compare=False)
    name: str = field(default="", compare=False)

    @property
    def root_nodes(self) -> tuple[str, ...]:
        """The nodes set by the experimenter (never given parents): ``roots``, or GLU's among the nodes."""
        if self.roots is not None:
            return self.roots
        return tuple(n for n in ROOT_NODES if n in self.affordance_nodes)

    @property
    def nodes(self) -> tuple[str, ...]:
        """All node names, affordance nodes first."""
        return tuple(self.values)

    @property
    def affordance_nodes(self) -> tuple[str, ...]:
        """The affordance nodes (actions, object features, effects), in K2 order."""
        return self.nodes[: self.n_affordance]

    @property
    def word_nodes(self) -> tuple[str, ...]:
        """The word nodes, in file order."""
        return self.nodes[self.n_affordance :]

    def cardinality(self, node: str) -> int:
        """Number of values of ``node``."""
        return len(self.values_of(node))

    def values_of(self, node: str) -> tuple[str, ...]:
        """The values of ``node``; raises :class:`UnknownNodeError` for an unknown node."""
        try:
            return self.values[node]
        except KeyError:
            raise UnknownNodeError(unknown_node_message(node, self.nodes)) from None

    def value_index(self, node: str, value: str) -> int:
        """Index of ``value`` among the values of ``node`` (aliases such as ``circle`` accepted)."""
        vals = self.values_of(node)
        value = self.aliases.get(node, {}).get(value, value)
        try:
            return vals.index(value)
        except ValueError:
            raise UnknownValueError(f"{node} has no value {value!r}; allowed: {', '.join(vals)}") from None


def action_node(schema: Schema) -> str:
    """The node the gesture HMMs observe: the schema's node with ``role: action``.

    A schema without roles (GLU's models saved before roles were stored, a network imported from BIF,
    XMLBIF or UAI) falls back to the node named ``Action``. Raises :class:`DataError` (one line) when there is
    no such node, or several nodes with the role action.

    >>> action_node(default_schema())
    'Action'
    """
    actions = [n for n in schema.affordance_nodes if schema.roles.get(n) == "action"]
    if len(actions) == 1:
        return actions[0]
    if len(actions) > 1:
        raise DataError(
            f"the schema gives several nodes the role action ({', '.join(actions)}); fusion with gestures "
            "needs one: name it with action=NODE"
        )
    if "Action" in schema.values:
        return "Action"
    raise DataError(
        "the network has no action node: give one node `role: action` in its schema "
        f"(nodes: {', '.join(schema.affordance_nodes[:8])})"
    )


def unknown_node_message(node: str, nodes: Sequence[str]) -> str:
    """One line naming an unknown node, the closest known names, and where the full list is."""
    import difflib

    close = difflib.get_close_matches(node, nodes, n=3, cutoff=0.6)
    hint = f" (did you mean {', '.join(close)}?)" if close else ""
    shown = ", ".join(nodes[:8]) + (f", … ({len(nodes)} nodes)" if len(nodes) > 8 else "")
    return f"unknown node {node!r}{hint}; nodes are: {shown}"


def default_schema() -> Schema:
    """GLU's schema (``glu/resources/schemas/glu.json``): 8 affordance nodes and 49 binary word nodes."""
    return schema_from_dict(_GLU, str(GLU_SCHEMA_FILE))


def schema_from_dict(d: Any, where: str = "schema") -> Schema:
    """A :class:`Schema` from a schema file's content; :class:`DataError` naming ``where`` if malformed."""
    if not isinstance(d, Mapping) or d.get("format", SCHEMA_FORMAT) != SCHEMA_FORMAT:
        raise DataError(f'{where}: not a glu schema (expected "format": "{SCHEMA_FORMAT}")')
    if d.get("version", SCHEMA_VERSION) != SCHEMA_VERSION:
        raise DataError(f"{where}: version {d.get('version')!r}; this glu reads version {SCHEMA_VERSION}")
    nodes, words = d.get("nodes"), d.get("words", [])
    if not isinstance(nodes, list) or not nodes:
        raise DataError(f"{where}: 'nodes' must be a non-empty list of {{name, values, role}}")
    if not isinstance(words, list) or not all(isinstance(w, str) and w.strip() == w and w for w in words):
        raise DataError(f"{where}: 'words' must be a list of words (non-empty, no spaces around)")
    values: dict[str, tuple[str, ...]] = {}
    roles: dict[str, str] = {}
    roots = []
    for i, n in enumerate(nodes, start=1):
        if not isinstance(n, Mapping) or not isinstance(n.get("name"), str) or not n["name"]:
            raise DataError(f"{where}: node {i} needs a 'name'")
        name = n["name"]
        vals = n.get("values")
        if not isinstance(vals, list) or len(vals) < 2 or not all(isinstance(v, str) and v for v in vals):
            raise DataError(f"{where}: node {name!r} needs a list of at least two value names")
        if len(set(vals)) != len(vals):
            raise DataError(f"{where}: node {name!r} lists a value twice")
        if name in values:
            raise DataError(f"{where}: node {name!r} is defined twice")
        role = n.get("role")
        if role not in ROLES:
            raise DataError(f"{where}: node {name!r}: role {role!r}; allowed: {', '.join(ROLES)}")
        unknown = set(n) - {"name", "values", "role", "set_by_experimenter", "description"}
        if unknown:
            raise DataError(f"{where}: node {name!r}: unknown key(s) {sorted(unknown)}")
        values[name], roles[name] = tuple(vals), role
        if n.get("set_by_experimenter", False):
            roots.append(name)
    clash = sorted(set(words) & set(values))
    if clash or len(set(words)) != len(words):
        raise DataError(
            f"{where}: words must be distinct and differ from node names: {clash or 'a word twice'}"
        )
    aliases = d.get("aliases", {})
    if not isinstance(aliases, Mapping) or any(
        k not in values or not isinstance(v, Mapping) for k, v in aliases.items()
    ):
        raise DataError(f"{where}: 'aliases' maps node names to {{alias: value}}")
    for node, amap in aliases.items():
        for alias, v in amap.items():
            if v not in values[node]:
                raise DataError(f"{where}: alias {alias!r} of {node!r} names an unknown value {v!r}")
            if alias in values[node] and alias != v:  # would silently relabel every row of that value
                raise DataError(
                    f"{where}: alias {alias!r} of {node!r} is itself one of its values; an alias is another "
                    f"name for a value, not a way to merge {alias!r} into {v!r}"
                )
    all_values = dict(values)
    all_values.update({w: WORD_VALUES for w in words})
    return Schema(
        values=all_values,
        n_affordance=len(values),
        aliases={k: dict(v) for k, v in aliases.items()},
        roots=tuple(roots),
        roles=roles,
        name=str(d.get("name", "")),
    )


def read_schema_file(path: str | os.PathLike) -> Schema:
    """Read a schema file (``.json``, or ``.yaml``/``.yml``, see the module docstring)."""
    path = Path(path)
    text = read_text(path, "schema file")
    if path.suffix.lower() in (".yaml", ".yml"):
        import yaml

        try:
            d = yaml.safe_load(text)
        except yaml.YAMLError as e:
            raise DataError(f"{path}: not YAML ({str(e).splitlines()[0]})") from None
    else:
        try:
            d = json.loads(text)
        except json.JSONDecodeError as e:
            raise DataError(f"{path}: not JSON ({e})") from None
    return schema_from_dict(d, str(path))


def schema_to_dict(schema: Schema) -> dict[str, Any]:
    """The content of a schema file for ``schema`` (inverse of :func:`schema_from_dict`)."""
    return {
        "format": SCHEMA_FORMAT,
        "version": SCHEMA_VERSION,
        "name": schema.name,
        "nodes": [
            {
                "name": n,
                "values": list(schema.values_of(n)),
                "role": schema.roles.get(n, "object"),
                "set_by_experimenter": n in schema.root_nodes,
            }
            for n in schema.affordance_nodes
        ],
        "words": list(schema.word_nodes),
        "aliases": {k: dict(v) for k, v in schema.aliases.items()},
    }
