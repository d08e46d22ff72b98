"""``glu bn learn|edges|import`` and ``glu query``: learn the network, inspect it, ask it questions."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from glu.errors import EvidenceError, GluError


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``bn`` command group and ``query``."""
    p = sub.add_parser(
        "bn", help="learn, import or inspect the Affordance–Words network", description=__doc__
    )
    bsub = p.add_subparsers(dest="bn_command", metavar="SUBCOMMAND")
    bsub.required = True

    lp = bsub.add_parser("learn", help="learn structure (K2 + BIC) and parameters from the experiments")
    add_data_args(lp)
    lp.add_argument("-o", "--out", type=Path, required=True, help="model file to write (JSON)")
    lp.set_defaults(func=_learn)

    ep = bsub.add_parser("edges", help="print the edges of a model, one 'Parent -> Child' per line, sorted")
    ep.add_argument("model", type=Path, help="model file (.json from `glu bn learn`, or the original .mat)")
    ep.set_defaults(func=_edges)

    ip = bsub.add_parser("import", help="convert an original BNT model (BN_lab.mat) to a glu JSON model")
    ip.add_argument("mat", type=Path, help="the .mat file, e.g. reference-models/BN_lab.mat")
    ip.add_argument("-o", "--out", type=Path, required=True, help="model file to write (JSON)")
    ip.set_defaults(func=_import)

    q = sub.add_parser(
        "query",
        help="posterior marginals given hard and soft evidence",
        description="Posterior marginal of each target node given evidence, by exact inference.",
    )
    add_model_args(q)
    q.add_argument(
        "--target", action="extend", nargs="+", default=[], metavar="NODE", help="node(s) to infer"
    )
    add_evidence_args(q)
    q.add_argument("--json", action="store_true", help='print {"NODE": {"VALUE": p, …}, …} only')
    q.add_argument("--batch", metavar="QUERIES.jsonl",
                   help="one JSON query a line ({'target': [...], 'evidence': {...}, 'soft': {...}}); '-' = stdin")  # fmt: skip
    q.set_defaults(func=_query)


def add_data_args(p: argparse.ArgumentParser) -> None:
    """``--data``, ``--words``, ``--unseen-words``: where the network is learned from, and how."""
    p.add_argument(
        "--data", help="data folder, or 'synthetic' (default: $GLU_DATA_DIR, data/real, else synthetic)"
    )
    p.add_argument("--words", choices=("lab", "asr"), default="lab",
                   help="descriptions: lab = transcriptions (the paper's), asr = speech recogniser")  # fmt: skip
    p.add_argument("--unseen-words", choices=("zero", "uniform"), default="zero",
                   help="CPT rows of word parent configurations never seen: zero (the original's) or uniform")  # fmt: skip


def add_model_args(p: argparse.ArgumentParser) -> None:
    """``--model`` or the data options of :func:`add_data_args` (read by :func:`load_model`)."""
    p.add_argument(
        "--model", type=Path, help="model file (.json or the original .mat); default: learn from --data"
    )
    add_data_args(p)


def add_evidence_args(p: argparse.ArgumentParser) -> None:
    """``--evidence``, ``--soft``, ``--soft-rule`` (read by :func:`parse_evidence` and :func:`parse_soft`)."""
    p.add_argument(
        "--evidence", action="extend", nargs="+", default=[], metavar="NODE=VALUE", help="hard evidence"
    )
    p.add_argument(
        "--soft", action="append", default=[], metavar="NODE=v1:p1,v2:p2,…",
        help="soft evidence on an affordance node, a distribution over its values, "
        "e.g. a gesture posterior Action=grasp:0.2,tap:0.6,touch:0.2",
    )  # fmt: skip
    p.add_argument("--soft-rule", choices=("virtual", "jeffrey"), default="virtual",
                   help="how soft evidence enters: virtual (likelihood) evidence, as the originals, or Jeffrey's rule")  # fmt: skip


def load_model(args: argparse.Namespace):
    """The model named by ``--model``, or the one learned from ``--data``; returns (BayesNet, description)."""
    from glu.bn.model import BayesNet

    model = getattr(args, "model", None)
    if model is not None:
        if getattr(args, "data", None):
            raise EvidenceError("give either --model or --data, not both")
        bn = BayesNet.from_bnt_mat(model) if model.suffix.lower() == ".mat" else BayesNet.load(model)
        return bn, f"model {model} ({bn.meta.get('data_source', 'unknown data')})"
    from glu.bn.learning import learn_bn
    from glu.data.source import load_experiments, resolve_data

    source = resolve_data(args.data)
    df = load_experiments(source, args.words)
    bn = learn_bn(df, unseen_words=args.unseen_words)
    return bn, f"learned from {df.attrs['data_source']}, unseen words {args.unseen_words}"


def _learn(args: argparse.Namespace) -> int:
    bn, desc = load_model(args)
    bn.save(args.out)
    print(f"# {desc}", file=sys.stderr)
    print(f"wrote {args.out}: {len(bn.edges())} edges, zero CPT rows: {bn.zero_rows() or 'none'}")
    return 0


def _edges(args: argparse.Namespace) -> int:
    args.data = None
    bn, _ = load_model(args)
    for parent, child in bn.edges():
        print(f"{parent} -> {child}")
    return 0


def _import(args: argparse.Namespace) -> int:
    from glu.bn.model import BayesNet

    bn = BayesNet.from_bnt_mat(args.mat)
    bn.save(args.out)
    print(f"wrote {args.out}: {len(bn.edges())} edges (imported from {args.mat})")
    return 0


def parse_evidence(items: list[str]) -> dict[str, str]:
    """``["Action=tap", "Shape=sphere"]`` → ``{"Action": "tap", "Shape": "sphere"}``; a node twice is an error."""
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


def parse_soft(items: list[str]) -> dict[str, dict[str, float]]:
    """``["Action=grasp:0.2,tap:0.6,touch:0.2"]`` → ``{"Action": {"grasp": 0.2, …}}``."""
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


def _answer(
    bn, engine, targets: list[str], evidence: dict, soft: dict, rule: str
) -> dict[str, dict[str, float]]:
    if not targets:
        raise EvidenceError("no target: give at least one --target NODE")
    res = engine.query(targets, evidence, soft or None, rule)
    return {t: {v: float(p) for v, p in zip(bn.schema.values_of(t), res[t], strict=True)} for t in targets}


def _query(args: argparse.Namespace) -> int:
    from glu.bn.inference import InferenceEngine

    bn, desc = load_model(args)
    engine = InferenceEngine(bn)
    if args.batch:
        return _query_batch(args, bn, engine, desc)
    evidence = parse_evidence(args.evidence)
    soft = parse_soft(args.soft)
    both = sorted(set(evidence) & set(soft))
    if both:
        raise EvidenceError(f"{both[0]} is given twice: as --evidence and as --soft")
    answer = _answer(bn, engine, args.target, evidence, soft, args.soft_rule)
    if args.json:
        print(f"# {desc}", file=sys.stderr)
        print(json.dumps(answer))
        return 0
    print(f"# {desc}")
    shown = [f"{k}={v}" for k, v in evidence.items()] + [
        f"{k}~({', '.join(f'{v}:{p:g}' for v, p in d.items())}, {args.soft_rule})" for k, d in soft.items()
    ]
    print(f"# evidence: {', '.join(shown) if shown else 'none'}")
    width = max(len(t) for t in answer)
    for t, dist in answer.items():
        vwidth = max(len(v) for v in dist)
        for v, prob in dist.items():
            print(f"{t:<{width}}  {v:<{vwidth}}  {prob:.6f}")
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
        out.write(json.dumps(answer) + "\n")
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
    both = sorted(set(evidence) & set(soft))
    if both:
        raise EvidenceError(f"line {i}: {both[0]} is given twice: as evidence and as soft evidence")
    rule = q.get("soft_rule", default_rule)
    try:
        return _answer(bn, engine, targets, evidence, soft, rule)
    except GluError as e:
        raise type(e)(f"line {i}: {e}") from None
