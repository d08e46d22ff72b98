"""Figures of the verbal descriptions: N-best lists, "and" against "but", sampling against the exact search.

Every function draws on the axes it is given, first argument, and returns them: ``plot_x(ax, frame, …)``;
:func:`and_but_figure` builds the whole "and"/"but" figure, :func:`nbest_figure` one N-best list's and
:func:`sampling_figure` one random sample's against the grammar. N-best lists are dot plots (a score per
sentence, rank 1 at the top): their x axis spans the scores only, which a bar's length would exaggerate.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from glu.evidence import format_evidence
from glu.plots.style import ORIGINAL_MARK, WORD_COLORS, legend_right, new_figure
from glu.studies.replication.verbal import SamplingExample

SCORE_LABELS: dict[str, str] = {
    "paper": "score: (1/L) Σ log p(word | evidence)",
    "original": "score: (1 + Σ log p(word | evidence)) / L",
}
"""Axis label of each sentence score (:data:`glu.language.SCORES`)."""
OTHER_COLOR = "0.35"
"""Sentences with neither highlighted word."""


def _sentence_color(sentence: str, highlight: str | None) -> str:
    words = sentence.split()
    if highlight is not None and highlight in words:
        return WORD_COLORS.get(highlight, "#DD8452")
    for w, c in WORD_COLORS.items():
        if w in words:
            return c
    return OTHER_COLOR


def plot_nbest(
    ax: Axes,
    nbest: pd.DataFrame,
    title: str | None = None,
    highlight: str | None = None,
    score: str = "paper",
) -> Axes:
    """A dot plot of the scores of an N-best list: rank 1 at the top, the ranked sentences as labels.

    Each score is also written in a column right of the axes.

    Parameters
    ----------
    nbest : DataFrame with columns sentence and score (as returned by :func:`glu.language.nbest`)
    highlight : a word; sentences containing it are drawn in its colour (:data:`WORD_COLORS`)
    score : the name of the score (:data:`SCORE_LABELS`), for the axis label
    """
    df = nbest.reset_index(drop=True)
    y = np.arange(len(df))
    scores = df["score"].to_numpy(dtype=float)
    finite = np.isfinite(scores)
    colors = [_sentence_color(s, highlight) for s in df["sentence"]]
    ax.scatter(
        scores[finite], y[finite], s=28, c=[c for c, f in zip(colors, finite, strict=True) if f], zorder=3
    )
    ax.grid(axis="y", color="0.9", lw=0.8)
    ax.set_axisbelow(True)
    ranks = df["rank"] if "rank" in df else pd.Series(y + 1)
    ax.set_yticks(y, [f"{r}. {s}" for r, s in zip(ranks, df["sentence"], strict=True)], fontsize=8)
    for yi, v in zip(y, scores, strict=True):
        text = f"{v:.4f}".replace("-", "−") if np.isfinite(v) else "−∞"
        ax.text(1.02, yi, text, va="center", fontsize=7.5, color="0.2", transform=ax.get_yaxis_transform())
    ax.set_ylim(len(df) - 0.5, -0.5)
    if finite.any():
        lo, hi = float(scores[finite].min()), float(scores[finite].max())
        pad = max(0.08 * (hi - lo), 0.002)
        ax.set_xlim(lo - pad, hi + pad)
    ax.xaxis.set_major_locator(MaxNLocator(4))
    ax.set_xlabel(SCORE_LABELS[score] + " (higher is better)", fontsize=9)
    if title:
        ax.set_title(title, fontsize=9, loc="right")
    return ax


def plot_and_but(ax: Axes, probs: pd.DataFrame) -> Axes:
    """Grouped bars of P(and | e) and P(but | e) per evidence set, each labelled with its word and value.

    ``probs``: columns ObjVel, word, p (as :func:`glu.studies.replication.verbal.and_but_probabilities`),
    and ``paper_p`` when compared with TCDS 2020 Fig. 7 (drawn as black marks).
    """
    groups = list(dict.fromkeys(probs["ObjVel"]))
    words = list(dict.fromkeys(probs["word"]))
    x = np.arange(len(groups))
    width = 0.8 / max(len(words), 1)
    for k, w in enumerate(words):
        sub = probs[probs["word"] == w].set_index("ObjVel").reindex(groups)
        xs = x + (k - (len(words) - 1) / 2) * width
        bars = ax.bar(xs, sub["p"], width, color=WORD_COLORS.get(w, OTHER_COLOR), edgecolor="0.2", lw=0.5)
        ax.bar_label(bars, labels=[f'"{w}"\n{p:.2f}' for p in sub["p"]], fontsize=8, padding=2)
        if "paper_p" in sub:
            label = "TCDS 2020 Fig. 7 (published)" if k == 0 else None
            ax.plot(xs, sub["paper_p"], **{**ORIGINAL_MARK, "markersize": 18}, label=label)
    ax.set_xticks(x, [f"ObjVel=\n{g}" for g in groups])
    ax.set_xlabel("evidence: Action=grasp and")
    ax.set_ylim(0, 1.1)
    ax.set_yticks(np.linspace(0, 1, 6))
    ax.set_ylabel("p(word | evidence)")
    if "paper_p" in probs:
        ax.legend(fontsize=8, frameon=False, loc="lower center", bbox_to_anchor=(0.5, 1.0))
    return ax


def and_but_figure(probs: pd.DataFrame, lists: pd.DataFrame, score: str = "paper") -> Figure:
    """TCDS Fig. 7: P(and), P(but) per evidence (left) beside the N-best list of each evidence (right).

    ``lists``: the N-best lists, columns ObjVel, evidence, rank, sentence, score
    (:func:`glu.studies.replication.verbal.and_but_nbest`); sentences with "and" and "but" in their colours.
    """
    groups = list(lists.groupby("ObjVel", sort=False))
    fig = plt.figure(figsize=(10.5, 2.4 + 2.1 * len(groups)), layout="constrained")
    grid = fig.add_gridspec(len(groups), 2, width_ratios=[0.8, 1.6])
    plot_and_but(fig.add_subplot(grid[:, 0]), probs)
    for k, (_, sub) in enumerate(groups):
        plot_nbest(
            fig.add_subplot(grid[k, 1]), sub, title=str(sub["evidence"].iloc[0]), highlight="but", score=score
        )
    return fig


def plot_sampling(
    ax: Axes,
    scores: np.ndarray,
    sample_scores: np.ndarray,
    exact_best: float,
    sample_best: float | None = None,
    score: str = "paper",
    title: str | None = None,
) -> Axes:
    """The score distribution of every sentence of the grammar against a random sample's, with both bests.

    Parameters
    ----------
    scores : the score of every sentence, shape (n_sentences,) (:func:`glu.language.all_scores`)
    sample_scores : the scores of the sampled sentences, shape (n_samples,)
    exact_best : the best score of the grammar
    sample_best : the best score of the sample (default: the max of ``sample_scores``)
    score : the name of the score (:data:`SCORE_LABELS`), for the axis label
    title : the first line of the title; the sentences scoring −∞ (not drawn) and why the sample's
        histogram differs from the grammar's are written below it
    """
    finite = scores[np.isfinite(scores)]
    fs = sample_scores[np.isfinite(sample_scores)]
    if len(finite) == 0:
        return ax
    bins = np.linspace(finite.min(), max(finite.max(), exact_best), 60)
    ax.hist(
        finite, bins=bins, density=True, color="#4C72B0", alpha=0.45, label=f"all {len(scores):,} sentences"
    )
    if len(fs):
        ax.hist(
            fs,
            bins=bins,
            density=True,
            histtype="step",
            lw=1.5,
            color="#DD8452",
            label=f"{len(sample_scores):,} random ones (HSGen-style)",
        )
    sb = float(fs.max()) if sample_best is None and len(fs) else sample_best
    if np.isfinite(exact_best):
        ax.axvline(exact_best, color="k", lw=1, label=f"exact best: {exact_best:.4f}")
    if sb is not None and np.isfinite(sb):
        ax.axvline(sb, color="tab:red", lw=1, ls="--", label=f"best of the sample: {sb:.4f}")
    ax.set_xlabel(SCORE_LABELS[score])
    ax.set_ylabel("density")
    legend_right(ax, fontsize=7.5)
    lines = [title] if title else []
    n_inf, m_inf = len(scores) - len(finite), len(sample_scores) - len(fs)
    if n_inf or m_inf:
        lines.append(
            f"not drawn, scoring −∞ (a word of probability 0): {n_inf:,} of the grammar's sentences "
            f"({100 * n_inf / len(scores):.0f} %), {m_inf:,} of the sample's "
            f"({100 * m_inf / max(len(sample_scores), 1):.0f} %)"
        )
    lines.append(
        "the sample is not uniform over sentences: HSGen picks each alternative with equal chance, so short\n"
        "branches (no size or colour, “grasps” rather than “has just grasped”) outweigh their share of the "
        "grammar"
    )
    ax.set_title("\n".join(lines), fontsize=8.5)
    return ax


def nbest_figure(
    nbest: pd.DataFrame, evidence: Mapping[str, str], score: str = "paper", candidates: str = "the samples"
) -> Figure:
    """One N-best list (:func:`plot_nbest`), titled by its evidence, its score and where its sentences come
    from (``candidates``)."""
    fig, (ax,) = new_figure(1, width=7, height=3.6)
    plot_nbest(ax, nbest, title=f"{format_evidence(evidence)} ({score} score, {candidates})", score=score)
    return fig


def sampling_figure(example: SamplingExample) -> Figure:
    """One random sample's scores against the whole grammar's (:func:`plot_sampling`), titled by its evidence
    and size (:func:`glu.studies.replication.verbal.sampling_example`)."""
    fig, (ax,) = new_figure(1, width=8.5, height=3.6)
    plot_sampling(
        ax,
        example.grammar_scores,
        example.sample_scores,
        example.exact_score,
        score=example.score,
        title=f"{format_evidence(example.evidence)}: one sample of {example.n_samples:,}",
    )
    return fig
