"""``glu bn learn|edges|nodes|import|export`` and ``glu query``: learn the network, inspect it, ask it
questions."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from glu.bn.exchange import FORMATS, ZERO_ROW_MODES
from glu.cli.commands import add_command, add_group
from glu.cli.common import (
    add_data_args,
    add_engine_args,
    add_evidence_args,
    add_json_option,
    add_model_args,
    add_out_option,
    add_renormalise_option,
    json_text,
    load_model,
    make_engine,
    read_evidence,
    read_model_file,
)
from glu.cli.terminal import one_line
from glu.errors import EvidenceError, GluError
from glu.evidence import check_disjoint, format_evidence


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``bn`` command group and ``query``."""
    bsub = add_group(
        sub,
        "bn",
        "Learn the Affordance–Words network from the robot's experiments, list its edges and "
        "nodes, or convert it from and to the exchange formats of other tools (BIF, XMLBIF, UAI). "
        "Questions to a network: glu query and glu describe.",
    )
    _register_learn_and_inspect(bsub)
    _register_exchange(bsub)
    _register_query(sub)


def _register_learn_and_inspect(bsub: argparse._SubParsersAction) -> None:
    """Add ``bn learn``, ``bn edges`` and ``bn nodes``."""
    lp = add_command(
        bsub,
        "learn",
        "Learn the network's structure (K2 with the BIC score) and its conditional probability tables from "
        "the experiments of --data, or from your own --schema and --experiments, and write it as a glu JSON "
        "model.",
        _learn,
        help="learn structure (K2 + BIC) and parameters from the experiments",
    )
    add_data_args(lp)
    add_out_option(lp, "MODEL", "model file to write (JSON)")
    ep = add_command(
        bsub,
        "edges",
        "Print the edges of a model, one 'Parent -> Child' per line, sorted by parent then child. --json "
        'prints [["Parent", "Child"], …].',
        _edges,
        help="print the edges of a model, one 'Parent -> Child' per line, sorted",
    )
    ep.add_argument("model", type=Path, help="model file (.json from glu bn learn, or the original .mat)")
    add_json_option(ep, "[[parent, child], …]")
    np_ = add_command(
        bsub,
        "nodes",
        "One line per node: its name, its kind (the schema's role — action, object, effect — for affordance "
        "nodes, 'word' for word nodes, 'node' when the file says nothing), its values and its parents. "
        "--json prints [{name, kind, values, parents}, …].",
        _nodes,
        help="list the nodes of a model: kind (role or word), values, parents",
    )
    np_.add_argument("model", type=Path, help="model file (.json, the original .mat, or .bif/.xmlbif/.uai)")
    add_json_option(np_, "[{name, kind, values, parents}, …]")


def _register_exchange(bsub: argparse._SubParsersAction) -> None:
    """Add ``bn import`` and ``bn export``."""
    ip = add_command(
        bsub,
        "import",
        "Read a BIF, XMLBIF or UAI file (the format from the suffix, or --format), or the originals' "
        "BN_lab.mat, validate it completely and write a glu JSON model. Indicator nodes seen__NODE written "
        "by glu bn export --zero-rows seen become NODE's all-zero rows again.",
        _import,
        help="convert a model from another tool (BIF, XMLBIF, UAI) or the original BNT .mat to a glu "
        "JSON model",
    )
    ip.add_argument("model", type=Path, metavar="FILE", help="e.g. net.bif, net.xmlbif, net.uai, BN_lab.mat")
    add_out_option(ip, "MODEL", "model file to write (JSON)")
    ip.add_argument("--format", choices=tuple(FORMATS), help="the input format (default: from the suffix)")
    add_renormalise_option(ip)
    xp = add_command(
        bsub,
        "export",
        "Write a glu model (JSON or the original .mat) in an exchange format. A model with the original's "
        "all-zero CPT rows is refused unless --zero-rows seen, which writes them as observed indicator nodes "
        "seen__NODE: give seen__NODE=yes as evidence in the other tool to get glu's posteriors exactly.",
        _export,
        help="write a model as BIF, XMLBIF or UAI, for pgmpy, pyAgrum, GeNIe, bnlearn, UAI solvers",
    )
    xp.add_argument(
        "model", type=Path, metavar="MODEL", help="model file (.json, the original .mat, or an exchange file)"
    )
    xp.add_argument("--format", choices=tuple(FORMATS), help="output format (default: from the suffix of -o)")
    add_out_option(xp, "FILE", "file to write (.bif, .xmlbif, .uai)")
    xp.add_argument(
        "--zero-rows",
        choices=ZERO_ROW_MODES,
        default=ZERO_ROW_MODES[0],
        help="all-zero CPT rows: refuse (default) or write them as observed indicator nodes (seen)",
    )
    add_renormalise_option(xp)


def _register_query(sub: argparse._SubParsersAction) -> None:
    q = add_command(
        sub, "query", "Posterior marginal of each target node given evidence, by exact inference.", _query
    )
    add_model_args(q)
    q.add_argument(
        "--target",
        action="extend",
        nargs="+",
        default=[],
        metavar="NODE",
        help=f"node(s) to infer; '{WORDS_TARGET}' = every word node's P(present)",
    )
    add_evidence_args(q)
    add_engine_args(q)
    add_json_option(q, '{"NODE": {"VALUE": p, …}, …}')
    q.add_argument(
        "--batch",
        metavar="QUERIES.jsonl",
        help="one JSON query a line ({'target': [...], 'evidence': {...}, 'soft': {...}}); '-' = stdin",
    )


def _learn(args: argparse.Namespace) -> int:
    bn, desc = load_model(args)
    bn.save(args.out)
    print(f"# {desc}", file=sys.stderr)
    print(f"wrote {args.out}: {len(bn.edges())} edges, zero CPT rows: {bn.zero_rows() or 'none'}")
    return 0


def _edges(args: argparse.Namespace) -> int:
    args.data = None
    bn, _ = load_model(args)
    if args.json:
        print(json_text([list(edge) for edge in bn.edges()]))
        return 0
    for parent, child in bn.edges():
        print(f"{one_line(parent)} -> {one_line(child)}")
    return 0


def node_kind(bn: Any, node: str) -> str:
    """What a node is: its schema role (action, object, effect), ``word``, or ``node`` when unknown."""
    if node in bn.schema.word_nodes:
        return "word"
    return bn.schema.roles.get(node, "node")


def _nodes(args: argparse.Namespace) -> int:
    args.data = None
    bn, desc = load_model(args)
    rows = [
        {
            "name": n,
            "kind": node_kind(bn, n),
            "values": list(bn.schema.values_of(n)),
            "parents": list(bn.parents[n]),
        }
        for n in bn.nodes
    ]
    if args.json:
        print(json_text(rows))
        return 0
    print(f"# {desc}: {len(rows)} nodes, {len(bn.schema.word_nodes)} of them word nodes")
    table = [("node", "kind", "values", "parents")] + [  # names read from a file, each shown on one line
        (
            one_line(r["name"]),
            r["kind"],
            ", ".join(map(one_line, r["values"])),
            ", ".join(map(one_line, r["parents"])) or "—",
        )
        for r in rows
    ]
    widths = [max(len(row[i]) for row in table) for i in range(3)]
    widths[2] = min(40, widths[2])
    for row in table:
        print("  ".join(f"{cell:<{w}}" for cell, w in zip(row[:3], widths, strict=True)) + f"  {row[3]}")
    return 0


def renormalised_text(meta: dict) -> str:
    """One line on the rows an import rescaled (``meta["renormalised"]``), or '' when none was."""
    r = meta.get("renormalised")
    if not r:
        return ""
    return (
        f"rescaled {r['rows']} CPT row(s) to sum to 1 (largest |1 − sum| = {r['largest_deviation']:.2g}, "
        f"in {r['at']}; tolerance {r['tolerance']:g})"
    )


def _import(args: argparse.Namespace) -> int:
    bn = read_model_file(args.model, args.format, renormalise=args.renormalise)
    bn.save(args.out)
    zr = bn.zero_rows()
    print(
        f"wrote {args.out}: {len(bn.nodes)} nodes, {len(bn.edges())} edges"
        + (f", all-zero CPT rows: {zr}" if zr else "")
        + f" (imported from {args.model})"
    )
    note = renormalised_text(bn.meta)
    if note:
        print(note)
    return 0


def _export(args: argparse.Namespace) -> int:
    from glu.bn.exchange import export_bn, format_of, seen_evidence

    fmt = format_of(args.out, args.format)
    bn = read_model_file(args.model, renormalise=args.renormalise)
    export_bn(bn, args.out, fmt, zero_rows=args.zero_rows)
    print(f"wrote {args.out} ({fmt}): {len(bn.nodes)} nodes, {len(bn.edges())} edges")
    seen = seen_evidence(bn) if args.zero_rows == "seen" else {}
    if seen:
        print(
            "the model's all-zero CPT rows are indicator nodes; in the other tool, always observe: "
            + " ".join(f"{k}={v}" for k, v in seen.items())
        )
    return 0


WORDS_TARGET = "words"
"""``--target words``: every word node's P(present) (unless the model has a node of that name)."""


def _answer(
    bn, engine, targets: list[str], evidence: dict, soft: dict, rule: str
) -> dict[str, dict[str, float]]:
    if not targets:
        raise EvidenceError("no target: give at least one --target NODE")
    words = WORDS_TARGET in targets and WORDS_TARGET not in bn.schema.values
    nodes = [t for t in targets if not (words and t == WORDS_TARGET)]
    res = engine.query(nodes, evidence, soft or None, rule) if nodes else {}
    out = {t: {v: float(p) for v, p in zip(bn.schema.values_of(t), res[t], strict=True)} for t in nodes}
    if words:
        if not engine.binary_leaves:
            raise EvidenceError(f"--target {WORDS_TARGET}: this model has no word nodes")
        probs = engine.word_probability_array(evidence, soft or None, rule)
        out[WORDS_TARGET] = {w: float(p) for w, p in zip(engine.binary_leaves, probs, strict=True)}
    return out


def _query(args: argparse.Namespace) -> int:
    bn, desc = load_model(args)
    engine = make_engine(bn, args)
    if args.batch:
        return _query_batch(args, bn, engine, desc)
    evidence, soft = read_evidence(args)
    answer = _answer(bn, engine, args.target, evidence, soft, args.soft_rule)
    if args.json:
        print(f"# {desc}", file=sys.stderr)
        print(json_text(answer))
        return 0
    print(f"# {desc}")
    print(f"# evidence: {format_evidence(evidence, soft, args.soft_rule) or 'none'}")
    words = (
        answer.pop(WORDS_TARGET) if WORDS_TARGET in answer and WORDS_TARGET not in bn.schema.values else None
    )
    answer = {one_line(t): {one_line(v): p for v, p in dist.items()} for t, dist in answer.items()}
    if answer:
        width = max(len(t) for t in answer)
        for t, dist in answer.items():
            vwidth = max(len(v) for v in dist)
            for v, prob in dist.items():
                print(f"{t:<{width}}  {v:<{vwidth}}  {prob:.6f}")
    if words is not None:
        words = {one_line(w): p for w, p in words.items()}
        wwidth = max(len("word"), *(len(w) for w in words))
        print(f"{'word':<{wwidth}}  P(present)")
        for w, prob in words.items():
            print(f"{w:<{wwidth}}  {prob:.6f}")
    return 0


def _query_batch(args: argparse.Namespace, bn, engine, desc: str) -> int:
    if args.target or args.evidence or args.soft:
        raise EvidenceError(
            "--batch takes its targets and evidence from the file; drop --target/--evidence/--soft"
        )
    if args.batch == "-":
        lines = sys.stdin.read().splitlines()
    else:
        try:
            lines = Path(args.batch).read_text(encoding="utf-8").splitlines()
        except FileNotFoundError:
            raise EvidenceError(f"{args.batch}: no such batch file") from None
        except (UnicodeDecodeError, OSError) as e:
            raise EvidenceError(f"{args.batch}: cannot read the batch file ({e})") from None
    print(f"# {desc}; {len(lines)} queries", file=sys.stderr)
    out = sys.stdout
    n_err = 0
    for i, line in enumerate(lines, start=1):
        try:
            answer: dict[str, Any] = _batch_line(bn, engine, line, i, args.soft_rule)
        except GluError as e:
            answer = {"error": str(e)}
            n_err += 1
        out.write(json_text(answer) + "\n")
    if n_err:
        print(f"# {n_err} of {len(lines)} queries answered with an error", file=sys.stderr)
    return 0


def _batch_line(bn, engine, line: str, i: int, default_rule: str) -> dict[str, Any]:
    if not line.strip():
        raise EvidenceError(f"line {i}: empty line; expected a JSON query")
    try:
        q = json.loads(line)
    except json.JSONDecodeError as e:
        raise EvidenceError(f"line {i}: not JSON ({e.msg} at column {e.colno})") from None
    if not isinstance(q, dict):
        raise EvidenceError(f"line {i}: expected a JSON object with 'target', 'evidence', 'soft'")
    unknown = set(q) - {"target", "evidence", "soft", "soft_rule"}
    if unknown:
        raise EvidenceError(
            f"line {i}: unknown key(s) {sorted(unknown)}; allowed: target, evidence, soft, soft_rule"
        )
    targets = q.get("target", [])
    targets = [targets] if isinstance(targets, str) else targets
    evidence = q.get("evidence") or {}
    soft = q.get("soft") or {}
    if not isinstance(targets, list) or not all(isinstance(t, str) for t in targets):
        raise EvidenceError(f"line {i}: 'target' must be a node name or a list of node names")
    if not isinstance(evidence, dict) or not all(isinstance(v, str) for v in evidence.values()):
        raise EvidenceError(f"line {i}: 'evidence' must map node names to value names")
    if not isinstance(soft, dict) or not all(isinstance(d, dict | list) for d in soft.values()):
        raise EvidenceError(f"line {i}: 'soft' must map node names to {{value: probability}}")
    try:
        check_disjoint(evidence, soft)
    except EvidenceError as e:
        raise EvidenceError(f"line {i}: {e}") from None
    rule = q.get("soft_rule", default_rule)
    from glu.bn.soft import SOFT_RULES

    if rule not in SOFT_RULES:
        raise EvidenceError(f"line {i}: unknown soft_rule {rule!r}; allowed: {', '.join(SOFT_RULES)}")
    try:
        return _answer(bn, engine, targets, evidence, soft, rule)
    except GluError as e:
        raise type(e)(f"line {i}: {e}") from None
