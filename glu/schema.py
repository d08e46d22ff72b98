"""The variables of the Affordance–Words model: node names, their values, and the 49 words.

Value order is the order of the original data files (METHOD.md §1) and is used everywhere: CPT axes,
posterior vectors, categorical columns. In glu the Shape value ``circle`` of the files is called
``sphere`` (the papers' name); ``circle`` is accepted as an alias on input. A word node takes the values
``absent`` and ``present`` (the files' ``-`` and the word itself).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from glu.errors import UnknownNodeError, UnknownValueError

AFFORDANCE_VALUES: dict[str, tuple[str, ...]] = {
    "Action": ("grasp", "tap", "touch"),
    "Color": ("green1", "green2", "yellow", "blue"),
    "Shape": ("sphere", "box"),
    "Size": ("small", "medium", "big"),
    "ObjVel": ("slow", "medium", "fast"),
    "ObjHandVel": ("slow", "medium", "fast"),
    "HandVel": ("slow", "fast"),
    "Contact": ("short", "long"),
}
"""Affordance nodes in the fixed K2 order, with their values in file order (glu names)."""

AFFORDANCE_NODES: tuple[str, ...] = tuple(AFFORDANCE_VALUES)
ACTIONS: tuple[str, ...] = AFFORDANCE_VALUES["Action"]
"""The actions, in the network's order: grasp, tap, touch (every p_HMM vector follows it)."""
ROOT_NODES: tuple[str, ...] = ("Action", "Color", "Shape", "Size")
"""Set by the experimenter: they never get parents."""

WORDS: tuple[str, ...] = (
    "the", "robot", "he", "baltazar",
    "grasps", "grasping", "grasped", "picks", "picking", "picked",
    "taps", "tapping", "tapped", "pushes", "pushing", "pushed",
    "touches", "touching", "touched", "pokes", "poking", "poked",
    "is", "has", "just",
    "big", "small", "green", "yellow", "blue",
    "ball", "sphere", "box", "square", "cube",
    "but", "and",
    "still", "inert", "moves", "moving", "rolls", "rolling", "slides", "sliding",
    "rises", "rising", "falls", "falling",
)  # fmt: skip
"""The 49 words of the vocabulary, in file order."""

WORD_VALUES: tuple[str, str] = ("absent", "present")

FILE_ALIASES: dict[str, dict[str, str]] = {"Shape": {"circle": "sphere"}}
"""Values as written in the original files → glu values."""


@dataclass(frozen=True)
class Schema:
    """Nodes of a model and their values: affordance nodes first (in K2 order), then word nodes.

    Attributes
    ----------
    values : mapping node → tuple of values, in order (affordance nodes first, then words)
    n_affordance : how many of the leading nodes are affordance nodes
    aliases : mapping node → {alias: value}, accepted on input
    """

    values: Mapping[str, tuple[str, ...]]
    n_affordance: int
    aliases: Mapping[str, Mapping[str, str]] = field(default_factory=dict)

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


def unknown_node_message(node: str, nodes: Sequence[str]) -> str:
    """One line naming an unknown node, the closest known names, and where the full list is."""
    import difflib

    close = difflib.get_close_matches(node, nodes, n=3, cutoff=0.6)
    hint = f" (did you mean {', '.join(close)}?)" if close else ""
    shown = ", ".join(nodes[:8]) + (f", … ({len(nodes)} nodes)" if len(nodes) > 8 else "")
    return f"unknown node {node!r}{hint}; nodes are: {shown}"


def default_schema() -> Schema:
    """The schema of the original data: 8 affordance nodes and 49 binary word nodes."""
    values: dict[str, tuple[str, ...]] = dict(AFFORDANCE_VALUES)
    values.update({w: WORD_VALUES for w in WORDS})
    return Schema(values=values, n_affordance=len(AFFORDANCE_VALUES), aliases=FILE_ALIASES)
