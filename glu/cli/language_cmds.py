"""``glu describe``: the best verbal descriptions of a situation, from the grammar and the BN's word probabilities."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import Any

from glu.cli.common import add_evidence_args, add_model_args, integer, load_model, positive_int, read_evidence
from glu.errors import EvidenceError
from glu.evidence import format_evidence

DESCRIPTION = """\
Print the N best sentences of the grammar given evidence, each scored by the mean log probability of
its words, p(word | evidence) from the Affordance-Words network (TCDS 2020). By default the N best are
exact, over every sentence of the grammar; --sample K ranks K random sentences instead (the originals'
method, as HTK's HSGen) and also prints the exact best for comparison.
"""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``describe``."""
    p = sub.add_parser(
        "describe",
        help="the N best sentences describing a situation (grammar + word probabilities)",
        description=DESCRIPTION,
    )
    add_model_args(p)
    add_evidence_args(p)
    p.add_argument(
        "--nbest", type=positive_int, default=10, metavar="N", help="how many sentences (default 10)"
    )
    p.add_argument("--sample", type=positive_int, metavar="K",
                   help="rank K random sentences (the originals' method) instead of the whole grammar")  # fmt: skip
    p.add_argument(
        "--seed", type=integer, metavar="S", help="seed of the random sentences (with --sample; default 0)"
    )
    p.add_argument(
        "--grammar", type=Path, metavar="FILE", help="grammar in HTK HParse syntax (default: glu's)"
    )
    p.add_argument("--must-contain", nargs="+", metavar="WORD",
                   help="only sentences with at least one of these words, e.g. green yellow blue")  # fmt: skip
    p.add_argument("--max-length", type=positive_int, metavar="L",
                   help="only sentences of at most L words (needed when the grammar repeats with { } or < >)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object only")
    p.set_defaults(func=_describe)


def _score_json(x: float) -> float | None:
    return None if not math.isfinite(x) else float(x)


def _describe(args: argparse.Namespace) -> int:
    from glu.bn.inference import InferenceEngine
    from glu.language.descriptions import nbest, rank_sentences, word_probabilities
    from glu.language.grammar import load_grammar
    from glu.language.sampling import sample_sentences
    from glu.language.sentences import compile_network, count_sentences

    if args.seed is not None and args.sample is None:
        raise EvidenceError("--seed chooses the random sentences of --sample K; give --sample too")
    if args.sample is not None and args.max_length is not None:
        raise EvidenceError("--max-length applies to the exact N-best; drop it with --sample")
    evidence, soft = read_evidence(args)
    grammar = load_grammar(args.grammar)
    net = compile_network(grammar)
    limit = net.check_length_limit(args.max_length)
    n_sentences = count_sentences(net, limit)
    bn, desc = load_model(args)
    engine = InferenceEngine(bn)
    probs = word_probabilities(engine, evidence, soft, args.soft_rule)

    t0 = time.perf_counter()
    exact = nbest(net, probs, args.nbest, max_length=args.max_length, must_contain=args.must_contain)
    t_exact = time.perf_counter() - t0
    result = exact
    seed = 0 if args.seed is None else args.seed
    n_distinct = None
    if args.sample is not None:
        drawn = sample_sentences(grammar, args.sample, seed)
        if args.must_contain:
            wanted = set(args.must_contain)
            drawn = [s for s in drawn if wanted & set(s)]
        n_distinct = len(set(drawn))
        result = rank_sentences(drawn, probs, args.nbest)

    gram_name = "glu default grammar" if args.grammar is None else str(args.grammar)
    if args.json:
        out: dict[str, Any] = {
            "model": desc,
            "grammar": {"source": gram_name, "n_sentences": n_sentences,
                        "min_length": net.min_length, "max_length": limit},
            "evidence": evidence, "soft": soft, "soft_rule": args.soft_rule,
            "must_contain": args.must_contain,
            "method": "exact" if args.sample is None else "sample",
            "nbest": [{"rank": int(r.rank), "sentence": r.sentence, "score": _score_json(r.score),
                       "length": int(r.length)} for r in result.itertuples()],
        }  # fmt: skip
        if args.sample is not None:
            out.update(n_samples=args.sample, seed=seed, n_distinct=n_distinct)
        if len(exact):
            out["exact_best"] = {
                "sentence": exact["sentence"].iloc[0],
                "score": _score_json(exact["score"].iloc[0]),
            }
        out["seconds_exact"] = t_exact
        print(json.dumps(out, allow_nan=False))
        return 0

    print(f"# model: {desc}")
    print(f"# grammar: {gram_name}: {n_sentences:,} sentences of {net.min_length}–{limit} words")
    print(f"# evidence: {format_evidence(evidence, soft, args.soft_rule) or 'none'}")
    if args.must_contain:
        print(f"# only sentences containing: {' or '.join(args.must_contain)}")
    if args.sample is None:
        print(f"# exact {args.nbest}-best over the whole grammar ({t_exact * 1000:.1f} ms)")
    else:
        print(f"# best {args.nbest} of {args.sample:,} random sentences (HSGen-like, seed {seed}; "
              f"{n_distinct:,} distinct)")  # fmt: skip
    if result.empty:
        print("# no sentence")
        return 0
    print(f"{'rank':>4}  {'score':>10}  sentence")
    for r in result.itertuples():
        print(f"{r.rank:>4}  {r.score:>10.6f}  {r.sentence}")
    if args.sample is not None and len(exact):
        e_sent, e_score = exact["sentence"].iloc[0], float(exact["score"].iloc[0])
        status = "drawn" if e_sent in set(result["sentence"]) else "not drawn"
        print(f"# exact best ({status}): {e_score:.6f}  {e_sent}")
    return 0
