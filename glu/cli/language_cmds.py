"""``glu describe``: the best verbal descriptions of a situation, from the grammar and the BN's word
probabilities."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Any

from glu.cli.commands import add_command
from glu.cli.common import (
    add_description_args,
    add_engine_args,
    add_evidence_args,
    add_json_option,
    add_model_args,
    json_text,
    load_model,
    make_engine,
    positive_int,
    read_candidates,
    read_evidence,
    say_to,
    seed,
)
from glu.cli.terminal import one_line
from glu.errors import EvidenceError
from glu.evidence import format_evidence
from glu.language.sampling import MAX_SAMPLES

DESCRIPTION = """\
Print the N best sentences describing a situation, each scored from the probabilities p(word | evidence)
of the Affordance-Words network (TCDS 2020). --score paper (default) is the papers' mean log probability
(1/L) Σ log p(w); --score original is what the originals' code printed, (1 + Σ log p(w))/L. By default the
N best are exact, over every sentence of the grammar; --candidates samples ranks the originals' 9,941
sampled sentences instead (with --score original this prints TCDS Table II, Fig. 7 and Fig. 8), and
--sample K ranks K new random sentences (as HTK's HSGen). With a candidate list the exact best is also
printed for comparison. --json prints [{"sentence": …, "score": …}, …] only; everything else goes to stderr.
"""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``describe``."""
    p = add_command(sub, "describe", DESCRIPTION, _describe)
    add_model_args(p)
    add_evidence_args(p)
    add_engine_args(p)
    add_description_args(p)
    p.add_argument(
        "--nbest", type=positive_int, default=10, metavar="N", help="how many sentences (default 10)"
    )
    p.add_argument(
        "--sample",
        type=_sample_count,
        metavar="K",
        help=f"rank K new random sentences of the grammar (as HSGen) instead of searching it "
        f"(1 to {MAX_SAMPLES:,})",
    )
    p.add_argument(
        "--seed", type=seed, metavar="S", help="seed of the random sentences (with --sample; default 0)"
    )
    p.add_argument(
        "--grammar", type=Path, metavar="FILE", help="grammar in HTK HParse syntax (default: glu's)"
    )
    p.add_argument(
        "--must-contain",
        nargs="+",
        metavar="WORD",
        help="only sentences with at least one of these words, e.g. green yellow blue",
    )
    p.add_argument(
        "--max-length",
        type=positive_int,
        metavar="L",
        help="only sentences of at most L words (needed when the grammar repeats with { } or < >)",
    )
    add_json_option(p, '[{"sentence": …, "score": …}, …] (best first; score null for −∞)')


def _sample_count(text: str) -> int:
    """--sample K: 1 ≤ K ≤ MAX_SAMPLES (memory grows with K)."""
    k = positive_int(text)
    if k > MAX_SAMPLES:
        raise argparse.ArgumentTypeError(f"at most {MAX_SAMPLES:,} random sentences at once, not {k:,}")
    return k


IMPOSSIBLE = "impossible"
"""How text output shows a score of −∞ (a word of the sentence has probability 0 under the evidence)."""


def _score_text(x: float) -> str:
    return f"{x:>10.5f}" if math.isfinite(x) else f"{IMPOSSIBLE:>10}"


SCORE_TEXT = {
    "paper": "(1/L) Σ log p(w), the papers' formula",
    "original": "(1 + Σ log p(w))/L, the originals' code",
}


def _describe(args: argparse.Namespace) -> int:
    from glu.language.descriptions import nbest, rank_sentences, word_probabilities
    from glu.language.grammar import load_grammar
    from glu.language.sampling import sample_sentences
    from glu.language.sentences import compile_network, count_sentences

    _check_options(args)
    evidence, soft = read_evidence(args)
    grammar = load_grammar(args.grammar)
    net = compile_network(grammar)
    limit = net.check_length_limit(args.max_length)
    if limit < net.min_length:
        raise EvidenceError(
            f"--max-length {limit}: the grammar's shortest sentence has {net.min_length} words; "
            f"give at least {net.min_length}"
        )
    n_sentences = count_sentences(net, limit)
    candidates = read_candidates(args)
    bn, desc = load_model(args)
    engine = make_engine(bn, args)
    vocabulary = list(net.words) + [w for c in candidates or () for w in c]
    probs = word_probabilities(engine, evidence, soft, args.soft_rule, vocabulary=vocabulary)

    t0 = time.perf_counter()
    exact = nbest(
        net, probs, args.nbest, max_length=args.max_length, must_contain=args.must_contain, score=args.score
    )
    t_exact = time.perf_counter() - t0
    result = exact
    seed = 0 if args.seed is None else args.seed
    if args.sample is not None:
        candidates = sample_sentences(grammar, args.sample, seed)
    if candidates is not None:
        result = rank_sentences(candidates, probs, args.nbest, args.score, args.must_contain)

    gram_name = "glu default grammar" if args.grammar is None else str(args.grammar)
    say = say_to(args.json)
    say(f"# model: {desc}")
    say(f"# grammar: {gram_name}: {n_sentences:,} sentences of {net.min_length}–{limit} words")
    say(f"# evidence: {format_evidence(evidence, soft, args.soft_rule) or 'none'}")
    say(f"# score: {args.score} = {SCORE_TEXT[args.score]}")
    others = probs.attrs["not_in_network"]
    if others:
        shown = ", ".join(others[:12]) + (f", … ({len(others)} words)" if len(others) > 12 else "")
        say(f"# words that are not network nodes score as p = 1 (function words): {shown}")
    if args.must_contain:
        say(f"# only sentences containing: {' or '.join(args.must_contain)}")
    if args.sample is not None:
        say(
            f"# best {args.nbest} of {args.sample:,} random sentences (HSGen-like, seed {seed}; "
            f"{len(set(candidates)):,} distinct)"
        )
    elif candidates is not None:
        what = "the originals' sampled sentences" if args.candidates == "samples" else args.candidates
        say(f"# best {args.nbest} of {len(set(candidates)):,} candidate sentences ({what})")
    else:
        say(f"# exact {args.nbest}-best over the whole grammar ({t_exact * 1000:.1f} ms)")
    if candidates is not None and len(exact):
        e_sent, e_score = exact["sentence"].iloc[0], float(exact["score"].iloc[0])
        status = "among the candidates" if e_sent in {" ".join(c) for c in candidates} else "not a candidate"
        say(f"# exact best over the grammar ({status}): {_score_text(e_score).strip()}  {e_sent}")
    _print_ranked(result, args.json, say)
    return 0


def _check_options(args: argparse.Namespace) -> None:
    """Refuse the options of ``describe`` that do not go together, before any work."""
    if args.seed is not None and args.sample is None:
        raise EvidenceError("--seed chooses the random sentences of --sample K; give --sample too")
    if args.sample is not None and args.max_length is not None:
        raise EvidenceError("--max-length applies to the exact N-best; drop it with --sample")
    if args.candidates != "grammar" and (args.sample is not None or args.max_length is not None):
        raise EvidenceError(
            f"--candidates {args.candidates} ranks a fixed list of sentences; "
            "--sample and --max-length apply to --candidates grammar only"
        )


def _print_ranked(result: Any, as_json: bool, say: Any) -> None:
    """The ranked sentences: a table on stdout (each sentence on one line), or JSON with −∞ as null."""
    if as_json:
        rows = [{"sentence": r.sentence, "score": float(r.score)} for r in result.itertuples()]  # −∞ → null
        print(json_text(rows))
        return
    if result.empty:
        print("# no sentence")
        return
    print(f"{'rank':>4}  {'score':>10}  sentence")
    for r in result.itertuples():
        print(f"{r.rank:>4}  {_score_text(r.score)}  {one_line(r.sentence)}")
    if not all(math.isfinite(x) for x in result["score"]):
        say(f"# {IMPOSSIBLE}: a word of the sentence has probability 0 under this evidence (score −∞)")
