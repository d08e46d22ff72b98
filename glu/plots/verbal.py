"""Figures of the verbal descriptions: N-best lists, "and" against "but", sampling against the exact search.

Every function draws on the axes it is given, first argument, and returns them: ``plot_x(ax, frame, …)``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.ticker import MaxNLocator

SCORE_LABELS: dict[str, str] = {
    "paper": "score: (1/L) Σ log p(word | evidence)",
    "original": "score: (1 + Σ log p(word | evidence)) / L",
}
"""Axis label of each sentence score (:data:`glu.language.SCORES`)."""


def plot_nbest(
    ax: Axes,
    nbest: pd.DataFrame,
    title: str | None = None,
    highlight: str | None = None,
    score: str = "paper",
) -> Axes:
    """Horizontal bars of the scores of an N-best list (rank 1 at the top), the sentences as labels.

    Parameters
    ----------
    ax : the axes to draw on
    nbest : DataFrame with columns sentence and score (as returned by :func:`glu.language.nbest`)
    title : axes title
    highlight : a word; bars of sentences containing it are drawn in a second colour
    score : the name of the score (:data:`SCORE_LABELS`), for the axis label

    Returns
    -------
    the Axes
    """
    df = nbest.reset_index(drop=True)
    y = np.arange(len(df))
    scores = df["score"].to_numpy(dtype=float)
    finite = np.isfinite(scores)
    colours = [
        "tab:orange" if highlight is not None and highlight in s.split() else "tab:blue"
        for s in df["sentence"]
    ]
    lo = hi = 0.0
    if finite.any():
        lo, hi = float(scores[finite].min()), float(scores[finite].max())
    pad = max(0.08 * (hi - lo), 0.005)
    left = lo - pad  # bars grow from the left edge: the longer, the better the sentence
    ax.barh(
        y[finite],
        scores[finite] - left,
        left=left,
        color=[c for c, f in zip(colours, finite, strict=True) if f],
    )
    ax.set_yticks(y, df["sentence"], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel(SCORE_LABELS[score])
    ax.set_xlim(left, hi + pad)
    ax.xaxis.set_major_locator(MaxNLocator(4))
    if title:
        ax.set_title(title, fontsize=9)
    return ax


def plot_and_but(ax: Axes, probs: pd.DataFrame) -> Axes:
    """Grouped bars of P(and | e) and P(but | e) per evidence set.

    Parameters
    ----------
    ax : the axes to draw on
    probs : DataFrame with columns ObjVel, word, p (as :func:`glu.experiments.verbal.and_but_probabilities`)

    Returns
    -------
    the Axes
    """
    groups = list(dict.fromkeys(probs["ObjVel"]))
    words = list(dict.fromkeys(probs["word"]))
    x = np.arange(len(groups))
    width = 0.8 / max(len(words), 1)
    for k, w in enumerate(words):
        sub = probs[probs["word"] == w].set_index("ObjVel").reindex(groups)
        bars = ax.bar(x + (k - (len(words) - 1) / 2) * width, sub["p"], width, label=f'"{w}"')
        ax.bar_label(bars, fmt="%.2f", fontsize=7)
    ax.set_xticks(x, [f"Action=grasp\nObjVel={g}" for g in groups])
    ax.set_ylim(0, 1.1)
    ax.set_ylabel("p(word | evidence)")
    ax.legend(fontsize=8)
    return ax


def plot_sampling(
    ax: Axes,
    scores: np.ndarray,
    sample_scores: np.ndarray,
    exact_best: float,
    sample_best: float | None = None,
    score: str = "paper",
) -> Axes:
    """The score distribution of every sentence of the grammar against a random sample's, with both bests.

    Parameters
    ----------
    ax : the axes to draw on
    scores : the score of every sentence, shape (n_sentences,) (:func:`glu.language.all_scores`)
    sample_scores : the scores of the sampled sentences, shape (n_samples,)
    exact_best : the best score of the grammar
    sample_best : the best score of the sample (default: the max of ``sample_scores``)
    score : the name of the score (:data:`SCORE_LABELS`), for the axis label

    Returns
    -------
    the Axes
    """
    finite = scores[np.isfinite(scores)]
    fs = sample_scores[np.isfinite(sample_scores)]
    if len(finite) == 0:
        return ax
    bins = np.linspace(finite.min(), max(finite.max(), exact_best), 60)
    n_inf = len(scores) - len(finite)
    extra = f" ({n_inf:,} score -inf)" if n_inf else ""
    ax.hist(finite, bins=bins, density=True, alpha=0.5, label=f"all {len(scores):,} sentences{extra}")
    if len(fs):
        ax.hist(
            fs,
            bins=bins,
            density=True,
            histtype="step",
            lw=1.5,
            label=f"{len(sample_scores):,} random ones"
            + (f" ({len(sample_scores) - len(fs):,} -inf)" if len(fs) < len(sample_scores) else ""),
        )
    sb = float(fs.max()) if sample_best is None and len(fs) else sample_best
    if np.isfinite(exact_best):
        ax.axvline(exact_best, color="k", lw=1, label=f"exact best: {exact_best:.4f}")
    if sb is not None and np.isfinite(sb):
        ax.axvline(sb, color="tab:red", lw=1, ls="--", label=f"best of the sample: {sb:.4f}")
    ax.set_xlabel(SCORE_LABELS[score])
    ax.set_ylabel("density")
    ax.legend(fontsize=7)
    return ax
