"""The verbal-description experiments of TCDS 2020 (METHOD.md §5), each a function returning a tidy DataFrame.

Every function takes an :class:`~glu.bn.InferenceEngine` (word probabilities given evidence) and
optionally a grammar (default: glu's, the originals' language) and uses the exact N-best of
:mod:`glu.language.descriptions`, not a random sample; :func:`sampling_vs_exact` measures what the originals'
random sample of 10,000 sentences misses. Each returns a frame stamped by
:func:`~glu.experiments.common.tidy`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from glu.experiments.common import evidence_text, model_source, tidy
from glu.language.descriptions import _network, all_scores, nbest, rank_sentences, word_probabilities
from glu.language.grammar import Grammar, load_grammar
from glu.language.sampling import sample_probability, sample_sentences
from glu.language.sentences import WordNetwork, compile_network

EVIDENCE_YELLOW_SPHERE: dict[str, str] = {
    "Color": "yellow",
    "Size": "big",
    "Shape": "sphere",
    "ObjVel": "fast",
}
"""A big yellow sphere that moved fast: the TCDS N-best example."""

EVIDENCE_AND_BUT: dict[str, dict[str, str]] = {
    "medium": {"Action": "grasp", "ObjVel": "medium"},
    "slow": {"Action": "grasp", "ObjVel": "slow"},
}
"""ObjVel → evidence: a grasp whose object then moved (expected: "and") or stayed still (expected: "but")."""

EVIDENCE_FIG8: tuple[dict[str, str], ...] = (
    {"Action": "grasp", "Color": "green1", "Size": "big", "Shape": "box", "ObjVel": "medium"},
    {"Action": "touch", "Color": "green1", "Size": "big", "Shape": "box", "ObjVel": "slow"},
    {"Action": "grasp", "Color": "green2", "Size": "small", "Shape": "sphere", "ObjVel": "medium"},
    {"Action": "touch", "Color": "green2", "Size": "big", "Shape": "sphere", "ObjVel": "slow"},
)
"""The four situations described by single sentences in TCDS Fig. 8."""

COLOUR_WORDS: tuple[str, ...] = ("green", "yellow", "blue")
"""The grammar's colour words."""
CONJUNCTIONS: tuple[str, ...] = ("and", "but")


def yellow_sphere_nbest(
    engine: Any, n: int = 10, grammar: Grammar | WordNetwork | None = None
) -> pd.DataFrame:
    """The exact ``n`` best descriptions of {Color=yellow, Size=big, Shape=sphere, ObjVel=fast}.

    Returns
    -------
    DataFrame with columns rank, sentence, score, length (``n`` rows, best first).
    """
    df = nbest(grammar, word_probabilities(engine, EVIDENCE_YELLOW_SPHERE), n)
    return tidy(
        df, "verbal_yellow_sphere_nbest", model_source(engine.bn), evidence=EVIDENCE_YELLOW_SPHERE, n=n
    )


def and_but_probabilities(engine: Any) -> pd.DataFrame:
    """P(and | e) and P(but | e) under {Action=grasp, ObjVel=medium} and {Action=grasp, ObjVel=slow}.

    Returns
    -------
    DataFrame with columns ObjVel, evidence, word, p; four rows (ObjVel medium, slow × and, but).
    """
    rows = []
    for objvel, ev in EVIDENCE_AND_BUT.items():
        probs = word_probabilities(engine, ev)
        for w in CONJUNCTIONS:
            rows.append({"ObjVel": objvel, "evidence": evidence_text(ev), "word": w, "p": float(probs[w])})
    df = pd.DataFrame(rows, columns=["ObjVel", "evidence", "word", "p"])
    return tidy(df, "verbal_and_but", model_source(engine.bn), evidence=EVIDENCE_AND_BUT)


def and_but_nbest(engine: Any, n: int = 10, grammar: Grammar | WordNetwork | None = None) -> pd.DataFrame:
    """The exact ``n`` best descriptions under each of the two and/but evidence sets.

    Returns
    -------
    DataFrame with columns ObjVel, evidence, rank, sentence, score, length, conjunction (the sentence's
    "and"/"but"); ``2 n`` rows, ObjVel medium first.
    """
    net = _network(grammar)
    frames = []
    for objvel, ev in EVIDENCE_AND_BUT.items():
        df = nbest(net, word_probabilities(engine, ev), n)
        df.insert(0, "evidence", evidence_text(ev))
        df.insert(0, "ObjVel", objvel)
        df["conjunction"] = [_conjunction(s) for s in df["sentence"]]
        frames.append(df)
    return tidy(pd.concat(frames, ignore_index=True), "verbal_and_but_nbest", model_source(engine.bn),
                evidence=EVIDENCE_AND_BUT, n=n)  # fmt: skip


def _conjunction(sentence: str) -> str:
    found = [w for w in sentence.split() if w in CONJUNCTIONS]
    return found[0] if found else ""


def best_with_colour(
    engine: Any, evidence: Mapping[str, str], grammar: Grammar | WordNetwork | None = None, n: int = 1
) -> pd.DataFrame:
    """The exact ``n`` best descriptions that name a colour (contain green, yellow or blue).

    Returns
    -------
    DataFrame with columns rank, sentence, score, length.
    """
    net = _network(grammar)
    colours = [w for w in COLOUR_WORDS if w in net.words]
    df = nbest(net, word_probabilities(engine, evidence), n, must_contain=colours)
    return tidy(df, "verbal_best_with_colour", model_source(engine.bn), evidence=evidence, n=n)


def fig8_descriptions(engine: Any, grammar: Grammar | WordNetwork | None = None) -> pd.DataFrame:
    """The single best description of each TCDS Fig. 8 situation, and the best one that names a colour.

    Returns
    -------
    DataFrame with columns situation (1–4), evidence, sentence, score, colour_sentence, colour_score; 4 rows.
    """
    net = _network(grammar)
    rows = []
    for k, ev in enumerate(EVIDENCE_FIG8, start=1):
        probs = word_probabilities(engine, ev)
        best = nbest(net, probs, 1).iloc[0]
        colour = nbest(net, probs, 1, must_contain=[w for w in COLOUR_WORDS if w in net.words]).iloc[0]
        rows.append({
            "situation": k, "evidence": evidence_text(ev),
            "sentence": best["sentence"], "score": float(best["score"]),
            "colour_sentence": colour["sentence"], "colour_score": float(colour["score"]),
        })  # fmt: skip
    return tidy(pd.DataFrame(rows), "verbal_fig8", model_source(engine.bn), evidence=EVIDENCE_FIG8)


def sampling_vs_exact(
    engine: Any,
    evidence: Mapping[str, str],
    seeds: Iterable[int] = range(10),
    n_samples: int = 10_000,
    n: int = 10,
    grammar: Grammar | None = None,
) -> pd.DataFrame:
    """What the originals' method (the best of ``n_samples`` random sentences) misses, one row per seed.

    Returns
    -------
    DataFrame with columns seed, n_samples, n_distinct (different sentences drawn), exact_best,
    exact_score, sample_best, sample_score, gap (exact_score − sample_score ≥ 0), found_best (the exact
    best was drawn), sample_rank (rank of the sample's best in the whole grammar: 1 + the number of
    sentences scoring higher), overlap (how many of the exact ``n`` best are among the sample's ``n`` best),
    p_draw_best (the probability that ``n_samples`` random sentences contain the exact best, computed from
    :func:`~glu.language.sentences.sample_probability`; the same on every row).
    """
    seeds = list(seeds)
    g = load_grammar() if grammar is None else grammar
    net = compile_network(g)
    probs = word_probabilities(engine, evidence)
    exact = nbest(net, probs, n)
    scores = np.sort(all_scores(net, probs))
    p_best = sample_probability(g, exact["sentence"].iloc[0])
    p_draw = -np.expm1(n_samples * np.log1p(-p_best)) if p_best < 1 else 1.0
    rows = []
    for seed in seeds:
        drawn = sample_sentences(g, n_samples, seed)
        ranked = rank_sentences(drawn, probs, n)
        s_best, s_score = ranked["sentence"].iloc[0], float(ranked["score"].iloc[0])
        tol = 1e-12 * max(1.0, abs(s_score))
        better = len(scores) - np.searchsorted(scores, s_score + tol, side="right")
        rows.append({
            "seed": seed, "n_samples": n_samples, "n_distinct": len(set(drawn)),
            "exact_best": exact["sentence"].iloc[0], "exact_score": float(exact["score"].iloc[0]),
            "sample_best": s_best, "sample_score": s_score,
            "gap": float(exact["score"].iloc[0]) - s_score,
            "found_best": s_best == exact["sentence"].iloc[0],
            "sample_rank": int(better) + 1,
            "overlap": len(set(exact["sentence"]) & set(ranked["sentence"])),
            "p_draw_best": float(p_draw),
        })  # fmt: skip
    return tidy(pd.DataFrame(rows), "verbal_sampling_vs_exact", model_source(engine.bn), evidence=evidence,
                seeds=seeds, n_samples=n_samples, n=n)  # fmt: skip
