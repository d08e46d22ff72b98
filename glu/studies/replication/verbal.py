"""The verbal-description experiments of TCDS 2020 (docs/method.md §7.5), each a function returning a tidy
DataFrame.

Every function takes an :class:`~glu.bn.Engine` (word probabilities given evidence) and
optionally a grammar (default: glu's, the originals' language). Two ways to choose a description:

* as the originals did: rank their 9,941 sampled sentences with their score ``(1 + Σ log p)/L``.
  :func:`published_descriptions` does that for TCDS Table II, Fig. 7 and Fig. 8 and puts the paper's
  printed sentences and scores (:mod:`glu.data.published`) beside glu's;
* exactly: the N best of the whole grammar (:mod:`glu.language.descriptions`), under either score.
  :func:`exact_vs_samples` compares the two; :func:`sampling_vs_exact` measures how often a random sample
  of 10,000 sentences misses the best of the grammar (:func:`trials_per_set` sums its trials up,
  :func:`sampling_example` draws one of them again for a figure).

Each returns a frame stamped by :func:`~glu.tidy.tidy`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.data.published import num2str, published
from glu.evidence import format_evidence
from glu.language.candidates import SentenceSet
from glu.language.descriptions import (
    DEFAULT_SCORE,
    SCORES,
    all_scores,
    describe,
    nbest,
    rank_sentences,
    score_sentence,
    score_sentences,
    word_network,
    word_probabilities,
)
from glu.language.grammar import Grammar, load_grammar
from glu.language.sampling import sample_probability, sample_sentences
from glu.language.sentences import WordNetwork, compile_network
from glu.tidy import model_source, tidy

Grammars = Grammar | WordNetwork | None
"""A grammar, one already compiled, or None: glu's (:func:`glu.language.descriptions.word_network`)."""
Sentences = Iterable[Iterable[str]] | None
"""Candidate sentences to rank (each a string or its words), or None: the exact search over the grammar."""

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
PUBLISHED_LISTS: dict[str, dict[str, str]] = {
    "table_ii": EVIDENCE_YELLOW_SPHERE,
    "fig7a": EVIDENCE_AND_BUT["medium"],
    "fig7b": EVIDENCE_AND_BUT["slow"],
}
"""The TCDS 10-best lists (keys of the published reference file) and their evidence."""


def yellow_sphere_nbest(
    engine, n: int = 10, grammar: Grammars = None, score: str = DEFAULT_SCORE, candidates: Sentences = None
) -> pd.DataFrame:
    """The ``n`` best descriptions of {Color=yellow, Size=big, Shape=sphere, ObjVel=fast} (TCDS Table II).

    Exact over the grammar, or ranked among ``candidates`` (see :func:`glu.language.describe`): a DataFrame
    with columns rank, sentence, score, length (``n`` rows, best first).
    """
    return _nbest_lists(engine, "verbal_yellow_sphere_nbest", None, n, grammar, score, candidates)


def and_but_probabilities(engine: Any, compare: bool = False) -> pd.DataFrame:
    """P(and | e) and P(but | e) under {Action=grasp, ObjVel=medium} and {Action=grasp, ObjVel=slow}.

    With ``compare``, the bars of TCDS Fig. 7 (:mod:`glu.data.published`) are added beside them.

    Returns
    -------
    DataFrame with columns ObjVel, evidence, word, p (and with ``compare``: paper_p, difference = p −
    paper_p, resolution of the published value); four rows (ObjVel medium, slow × and, but).
    """
    rows = []
    for objvel, ev in EVIDENCE_AND_BUT.items():
        probs = word_probabilities(engine, ev)
        for w in CONJUNCTIONS:
            rows.append({"ObjVel": objvel, "evidence": format_evidence(ev), "word": w, "p": float(probs[w])})
    df = pd.DataFrame(rows, columns=["ObjVel", "evidence", "word", "p"])
    if compare:
        bars = published()["conjunctions"]
        paper = {(r["ObjVel"], w): r[w] for r in bars["rows"] for w in CONJUNCTIONS}
        df["paper_p"] = [paper[o, w] for o, w in zip(df["ObjVel"], df["word"], strict=True)]
        df["difference"] = df["p"] - df["paper_p"]
        df["resolution"] = bars["resolution"]
    return _table(df, "verbal_and_but", engine, evidence=EVIDENCE_AND_BUT)


def and_but_nbest(
    engine, n: int = 10, grammar: Grammars = None, score: str = DEFAULT_SCORE, candidates: Sentences = None
) -> pd.DataFrame:
    """The ``n`` best descriptions under each of the two and/but evidence sets (TCDS Fig. 7).

    As :func:`yellow_sphere_nbest`, with the columns ObjVel, evidence, rank, sentence, score, length,
    conjunction (the sentence's "and"/"but"); ``2 n`` rows, ObjVel medium first.
    """
    return _nbest_lists(engine, "verbal_and_but_nbest", EVIDENCE_AND_BUT, n, grammar, score, candidates)


def _nbest_lists(
    engine: Any, name: str, sets: dict | None, n: int, grammar: Grammars, score: str, candidates: Sentences
) -> pd.DataFrame:
    """The lists of :func:`and_but_nbest` (``sets``) or :func:`yellow_sphere_nbest` (``sets`` None)."""
    net = word_network(grammar)
    cands = None if candidates is None else SentenceSet.of(candidates)
    frames = []
    for objvel, ev in (sets or {None: EVIDENCE_YELLOW_SPHERE}).items():
        df = describe(engine, ev, n=n, grammar=net, score=score, candidates=cands)
        if sets:
            df.insert(0, "evidence", format_evidence(ev))
            df.insert(0, "ObjVel", objvel)
            df["conjunction"] = [_conjunction(s) for s in df["sentence"]]
        frames.append(df)
    return _table(
        pd.concat(frames, ignore_index=True),
        name,
        engine,
        evidence=sets or EVIDENCE_YELLOW_SPHERE,
        n=n,
        score=score,
        candidates="grammar" if cands is None else "list",
    )


def _table(df: pd.DataFrame, name: str, engine: Any, **parameters: Any) -> pd.DataFrame:
    """``df`` stamped (:func:`~glu.tidy.tidy`) with the network's source and ``parameters``."""
    return tidy(df, name, model_source(engine.bn), **parameters)


def _conjunction(sentence: str) -> str:
    found = [w for w in sentence.split() if w in CONJUNCTIONS]
    return found[0] if found else ""


def fig8_descriptions(engine: Any, grammar: Grammars = None) -> pd.DataFrame:
    """The single best description of each TCDS Fig. 8 situation, and the best one that names a colour.

    Returns
    -------
    DataFrame with columns situation (1–4), evidence, sentence, score, colour_sentence, colour_score; 4 rows.
    """
    net = word_network(grammar)
    rows = []
    for k, ev in enumerate(EVIDENCE_FIG8, start=1):
        probs = word_probabilities(engine, ev)
        best = nbest(net, probs, 1).iloc[0]
        colour = nbest(net, probs, 1, must_contain=[w for w in COLOUR_WORDS if w in net.words]).iloc[0]
        rows.append(
            {
                "situation": k,
                "evidence": format_evidence(ev),
                "sentence": best["sentence"],
                "score": float(best["score"]),
                "colour_sentence": colour["sentence"],
                "colour_score": float(colour["score"]),
            }
        )
    return _table(pd.DataFrame(rows), "verbal_fig8", engine, evidence=EVIDENCE_FIG8)


def published_descriptions(engine: Any, candidates: Sentences, score: str = "original") -> pd.DataFrame:
    """TCDS Table II, Fig. 7(a), 7(b) and the four Fig. 8 sentences: the paper's beside glu's.

    Parameters
    ----------
    engine : inference engine of the Affordance–Words network
    candidates : the sentences to rank (the originals': their 9,941 samples,
        :meth:`glu.data.DataSource.sentence_samples`), or None for the exact search over the grammar
    score : ``"original"`` (what the paper printed) or ``"paper"`` (the paper's formula)

    Returns
    -------
    DataFrame, one row per published sentence (34): figure (table_ii, fig7a, fig7b, fig8a … fig8d), rank,
    evidence, paper_sentence, paper_score (as printed; None for Fig. 8, which prints no score), sentence,
    score (glu's), printed (glu's score as the originals' MATLAB printed it), same_sentence, same_score
    (the printed digits are equal; None for Fig. 8).
    """
    cands = None if candidates is None else SentenceSet.of(candidates)
    pub = published()["sentences"]
    jobs = [(key, pub[key]["evidence"], pub[key]["rows"], None) for key in PUBLISHED_LISTS]
    jobs += [(f"fig8{r['panel']}", r["evidence"], [r], list(COLOUR_WORDS)) for r in pub["fig8"]["rows"]]
    rows = []
    for key, ev, paper_rows, must in jobs:
        ours = describe(engine, ev, n=len(paper_rows), score=score, candidates=cands, must_contain=must)
        for k, (p, o) in enumerate(zip(paper_rows, ours.itertuples(), strict=True), start=1):
            printed = num2str(o.score)
            rows.append(
                {
                    "figure": key,
                    "rank": k,
                    "evidence": format_evidence(ev),
                    "paper_sentence": p["sentence"],
                    "paper_score": p.get("score"),
                    "sentence": o.sentence,
                    "score": float(o.score),
                    "printed": printed,
                    "same_sentence": o.sentence == p["sentence"],
                    "same_score": None if p.get("score") is None else printed == p["score"],
                }
            )
    what = "grammar" if cands is None else f"{len(set(map(tuple, cands)))} candidate sentences"
    return _table(
        pd.DataFrame(rows),
        "verbal_published_descriptions",
        engine,
        score=score,
        candidates=what,
        reference=published()["read_from"],
    )


def _rank_in(scores: np.ndarray, score: float) -> int:
    """1 + the number of ``scores`` higher than ``score`` (ties within 1e-12 count as equal); a count, so the
    9.3 million scores of the grammar need no sorting."""
    tol = 1e-12 * max(1.0, abs(score))
    return int(np.count_nonzero(scores > score + tol)) + 1


def exact_vs_samples(
    engine: Any,
    samples: Iterable[Iterable[str]],
    grammar: Grammar | None = None,
    evidence_sets: Mapping[str, Mapping[str, str]] = PUBLISHED_LISTS,
) -> pd.DataFrame:
    """The best description of the whole grammar against the best of the originals' samples, under both
    scores.

    Returns
    -------
    DataFrame, one row per (evidence set, score): figure, evidence, score_name, exact_best, exact_score,
    samples_best, samples_score, samples_rank (rank of the samples' best in the whole grammar, 1 = the
    best), exact_in_samples (the grammar's best is one of the samples), rank_under_other (rank of
    this score's exact best under the other score, in the whole grammar).
    """
    g = load_grammar() if grammar is None else grammar
    net = compile_network(g)
    sample_list = SentenceSet.of(samples)  # split and counted once for every evidence set and score
    sample_set = {" ".join(s) for s in sample_list}
    rows = []
    for key, ev in evidence_sets.items():
        probs = word_probabilities(engine, ev)
        every = {name: all_scores(net, probs, name) for name in SCORES}
        for name in SCORES:
            exact = nbest(net, probs, 1, score=name).iloc[0]
            best = rank_sentences(sample_list, probs, 1, name).iloc[0]
            other = next(o for o in SCORES if o != name)
            exact_under_other = score_sentence(exact["sentence"], probs, other)
            rows.append(
                {
                    "figure": key,
                    "evidence": format_evidence(ev),
                    "score_name": name,
                    "exact_best": exact["sentence"],
                    "exact_score": float(exact["score"]),
                    "samples_best": best["sentence"],
                    "samples_score": float(best["score"]),
                    "samples_rank": _rank_in(every[name], float(best["score"])),
                    "exact_in_samples": exact["sentence"] in sample_set,
                    "rank_under_other": _rank_in(every[other], exact_under_other),
                }
            )
    return _table(
        pd.DataFrame(rows),
        "verbal_exact_vs_samples",
        engine,
        n_samples=len(sample_set),
        evidence=dict(evidence_sets),
    )


def sampling_vs_exact(
    engine: Any,
    evidence: Mapping[str, str],
    seeds: Iterable[int] = range(10),
    n_samples: int = 10_000,
    n: int = 10,
    grammar: Grammar | None = None,
    score: str = DEFAULT_SCORE,
    drawn: Mapping[int, SentenceSet | list[str]] | None = None,
) -> pd.DataFrame:
    """What the originals' method (the best of ``n_samples`` random sentences) misses, one row per seed.

    ``drawn``: the samples already drawn, seed → ``sample_sentences(grammar, n_samples, seed)`` or its
    :class:`~glu.language.candidates.SentenceSet` (they do not depend on the evidence, so
    :func:`sampling_trials` draws and counts them once for every evidence set).

    Returns
    -------
    DataFrame with columns seed, n_samples, n_distinct (different sentences drawn), exact_best,
    exact_score, sample_best, sample_score, gap (exact_score − sample_score ≥ 0), found_best (the exact
    best was drawn), sample_rank (rank of the sample's best in the whole grammar: 1 + the number of
    sentences scoring higher), overlap (how many of the exact ``n`` best are among the sample's ``n`` best),
    p_draw_best (the probability that ``n_samples`` random sentences contain the exact best, computed from
    :func:`~glu.language.sampling.sample_probability`; the same on every row).
    """
    seeds = list(seeds)
    g = load_grammar() if grammar is None else grammar
    net = compile_network(g)
    probs = word_probabilities(engine, evidence)
    exact = nbest(net, probs, n, score=score)
    scores = all_scores(net, probs, score)
    p_best = sample_probability(g, exact["sentence"].iloc[0])
    p_draw = -np.expm1(n_samples * np.log1p(-p_best)) if p_best < 1 else 1.0
    rows = []
    for seed in seeds:
        sample = drawn[seed] if drawn is not None and seed in drawn else sample_sentences(g, n_samples, seed)
        ranked = rank_sentences(sample, probs, n, score)
        s_best, s_score = ranked["sentence"].iloc[0], float(ranked["score"].iloc[0])
        rows.append(
            {
                "seed": seed,
                "n_samples": n_samples,
                "n_distinct": len(set(sample)),
                "exact_best": exact["sentence"].iloc[0],
                "exact_score": float(exact["score"].iloc[0]),
                "sample_best": s_best,
                "sample_score": s_score,
                "gap": float(exact["score"].iloc[0]) - s_score,
                "found_best": s_best == exact["sentence"].iloc[0],
                "sample_rank": _rank_in(scores, s_score),
                "overlap": len(set(exact["sentence"]) & set(ranked["sentence"])),
                "p_draw_best": float(p_draw),
            }
        )
    return _table(
        pd.DataFrame(rows),
        "verbal_sampling_vs_exact",
        engine,
        evidence=evidence,
        seeds=seeds,
        n_samples=n_samples,
        n=n,
        score=score,
    )


def sampling_trials(
    engine: Any,
    seeds: Iterable[int],
    evidence_sets: Mapping[str, Mapping[str, str]] = PUBLISHED_LISTS,
    n_samples: int = 10_000,
    n: int = 10,
    grammar: Grammar | None = None,
    score: str = "original",
) -> pd.DataFrame:
    """:func:`sampling_vs_exact` for each evidence set (one trial per seed and set), in one frame.

    Returns
    -------
    DataFrame with the columns of :func:`sampling_vs_exact` plus figure (the key of the evidence set);
    ``len(seeds) × len(evidence_sets)`` rows.
    """
    seeds = list(seeds)
    g = load_grammar() if grammar is None else grammar
    # the same samples for every evidence set: drawn, split and counted once
    drawn = {seed: SentenceSet(sample_sentences(g, n_samples, seed)) for seed in seeds}
    frames = [
        sampling_vs_exact(engine, ev, seeds, n_samples, n, g, score, drawn).assign(figure=key)
        for key, ev in evidence_sets.items()
    ]
    return _table(
        pd.concat(frames, ignore_index=True),
        "verbal_sampling_trials",
        engine,
        seeds=seeds,
        evidence=dict(evidence_sets),
        n_samples=n_samples,
        score=score,
    )


def trials_per_set(trials: pd.DataFrame) -> pd.DataFrame:
    """:func:`sampling_trials` summed up per evidence set (``figure``, in the trials' order): trials, how many
    drew the grammar's best, the exact chance of that, the median rank of a sample's best in the grammar,
    the mean gap of its score to the best."""
    return trials.groupby("figure", sort=False).agg(
        trials=("seed", "size"),
        found_best=("found_best", "sum"),
        p_draw_best=("p_draw_best", "first"),
        median_rank=("sample_rank", "median"),
        mean_gap=("gap", "mean"),
    )


class SamplingExample(NamedTuple):
    """One trial of :func:`sampling_trials` drawn again (:func:`sampling_example`), for
    :func:`glu.studies.replication.verbal_figures.sampling_figure`."""

    evidence: dict[str, str]
    grammar_scores: np.ndarray
    sample_scores: np.ndarray
    exact_score: float
    n_samples: int
    score: str


def sampling_example(
    engine: Any,
    trials: pd.DataFrame,
    net: WordNetwork,
    grammar: Grammar,
    figure: str = "fig7a",
    score: str = "original",
) -> SamplingExample:
    """The first trial of the evidence set ``figure`` of ``trials`` (:func:`sampling_trials`, with the same
    ``score``): the score of every sentence of the grammar (``net``, compiled from ``grammar``) and of the
    trial's ``n_samples`` sentences, drawn again from its seed, and the grammar's best."""
    evidence = dict(PUBLISHED_LISTS[figure])
    probs = word_probabilities(engine, evidence)
    first = trials[trials["figure"] == figure].iloc[0]
    n_samples = int(first["n_samples"])
    drawn = sample_sentences(grammar, n_samples, int(first["seed"]))
    return SamplingExample(
        evidence,
        all_scores(net, probs, score),
        score_sentences(drawn, probs, score),
        first["exact_score"],
        n_samples,
        score,
    )
