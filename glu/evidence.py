"""Evidence as text: ``NODE=VALUE`` for hard evidence, ``NODE=v1:p1,v2:p2`` for soft evidence.

The one home of the evidence notation used on the command line, in batch files, in table columns and in
figure titles. Parsing checks the form only (a node given twice, a malformed pair); whether a node or a
value exists is checked by the model that receives the evidence.

>>> parse_evidence(["Action=tap", "Shape=sphere"])
{'Action': 'tap', 'Shape': 'sphere'}
>>> parse_soft(["Action=grasp:0.2,tap:0.6,touch:0.2"])
{'Action': {'grasp': 0.2, 'tap': 0.6, 'touch': 0.2}}
>>> format_evidence({"Action": "tap"}, {"Shape": {"sphere": 0.5, "box": 0.5}}, "jeffrey")
'Action=tap, Shape~(sphere:0.5, box:0.5, jeffrey)'
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from glu.errors import EvidenceError

SoftEvidence = Mapping[str, Mapping[str, float]]
"""Soft evidence: node → {value: probability}."""


def parse_evidence(items: Iterable[str]) -> dict[str, str]:
    """``["Action=tap", "Shape=sphere"]`` → ``{"Action": "tap", "Shape": "sphere"}``; a node twice is an
    error."""
    out: dict[str, str] = {}
    for item in items:
        node, sep, value = item.partition("=")
        node, value = node.strip(), value.strip()
        if not sep or not node or not value:
            raise EvidenceError(f"evidence {item!r} is malformed; expected NODE=VALUE, e.g. Action=tap")
        if node in out:
            raise EvidenceError(f"{node} is given twice in the evidence ({node}={out[node]} and {item})")
        out[node] = value
    return out


def parse_soft(items: Iterable[str]) -> dict[str, dict[str, float]]:
    """``["Action=grasp:0.2,tap:0.6,touch:0.2"]`` →
    ``{"Action": {"grasp": 0.2, "tap": 0.6, "touch": 0.2}}``."""
    out: dict[str, dict[str, float]] = {}
    for item in items:
        node, sep, spec = item.partition("=")
        node = node.strip()
        if not sep or not node or not spec.strip():
            raise EvidenceError(f"soft evidence {item!r} is malformed; expected NODE=v1:p1,v2:p2,…")
        if node in out:
            raise EvidenceError(f"{node} is given twice as soft evidence")
        dist: dict[str, float] = {}
        for part in spec.split(","):
            value, sep2, prob = part.partition(":")
            value = value.strip()
            try:
                p = float(prob)
            except ValueError:
                p = None
            if not sep2 or not value or p is None:
                raise EvidenceError(
                    f"soft evidence {item!r}: {part!r} is malformed; expected VALUE:PROBABILITY"
                )
            if value in dist:
                raise EvidenceError(f"soft evidence on {node} gives {value!r} twice")
            dist[value] = p
        out[node] = dist
    return out


def check_disjoint(evidence: Mapping[str, Any], soft: Mapping[str, Any] | None) -> None:
    """Refuse a node given both as hard and as soft evidence."""
    both = sorted(set(evidence) & set(soft or {}))
    if both:
        raise EvidenceError(f"{both[0]} is given twice: as hard evidence and as soft evidence")


def format_evidence(
    evidence: Mapping[str, Any] | None, soft: Mapping[str, Mapping[str, float]] | None = None, rule: str = ""
) -> str:
    """The evidence as one line: ``Action=tap, Shape=sphere`` (soft: ``Action~(grasp:0.2, …, virtual)``)."""
    parts = [f"{k}={v}" for k, v in (evidence or {}).items()]
    for node, dist in (soft or {}).items():
        inner = ", ".join(f"{v}:{p:g}" for v, p in dist.items()) + (f", {rule}" if rule else "")
        parts.append(f"{node}~({inner})")
    return ", ".join(parts)
