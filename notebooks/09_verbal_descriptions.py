# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     notebook_metadata_filter: kernelspec,jupytext,-jupytext.text_representation.format_version,-jupytext.text_representation.jupytext_version
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 09 · Verbal descriptions
#
# TCDS 2020 turns the network's word probabilities into sentences: a small grammar (HTK syntax) generates
# descriptions such as "the robot is tapping the ball and the ball is rolling", each scored by the mean log
# probability of its words given the evidence, `score(s) = (1/L) Σ_k log p(w_k | evidence)`. The originals
# ranked 10,000 random sentences; here the N best are exact, over every sentence of the grammar.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
words: str = "lab"  # descriptions: "lab" (the paper's) or "asr"
unseen_words: str = "zero"  # CPT rows of unseen word parents: "zero" (the original's) or "uniform"
nbest: int = 10  # sentences per N-best list
n_samples: int = 10_000  # random sentences per sample, as the originals
n_seeds: int = 20  # samples compared with the exact N-best
seed: int = 0  # first seed of the random samples
quick: bool = False  # small, fast run (for tests)
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
import time

import numpy as np

from glu import plots
from glu.bn import InferenceEngine, learn_bn
from glu.data import load_experiments
from glu.experiments import verbal as ex
from glu.language import (
    all_scores,
    count_sentences,
    default_network,
    load_grammar,
    sample_sentences,
    score_sentences,
    word_probabilities,
)
from glu.language import nbest as exact_nbest
from glu.notebook import start

out = start("09_verbal_descriptions", globals())
engine = InferenceEngine(learn_bn(load_experiments(out.source, words), unseen_words=unseen_words))
grammar, net = load_grammar(), default_network()
seeds = range(seed, seed + (2 if quick else n_seeds))
probs = word_probabilities(engine, ex.EVIDENCE_AND_BUT["slow"])
t0 = time.perf_counter()
exact_nbest(net, probs, nbest)
print(f"grammar: {count_sentences(net):,} sentences of {net.min_length}-{net.max_length} words; "
      f"exact {nbest}-best in {1000 * (time.perf_counter() - t0):.1f} ms")  # fmt: skip

# %% [markdown]
# ## "and" or "but": a grasp, then the object moves or stays still

# %%
and_but = ex.and_but_probabilities(engine)
lists = ex.and_but_nbest(engine, nbest)
out.table(and_but, "verbal_and_but_probabilities")
out.table(lists, "verbal_and_but_nbest")
fig, axes = plots.new_figure(3, width=4.6, height=3.6)
plots.plot_and_but(axes[0], and_but)
for ax, objvel in zip(axes[1:], ex.EVIDENCE_AND_BUT, strict=True):
    sub = lists[lists["ObjVel"] == objvel]
    plots.plot_nbest(ax, sub, title=sub["evidence"].iloc[0], highlight="but")
out.figure(fig, "verbal_and_but")
and_but

# %% [markdown]
# ## The big yellow sphere that moved fast, and the four situations of TCDS Fig. 8

# %%
yellow = ex.yellow_sphere_nbest(engine, nbest, net)
fig8 = ex.fig8_descriptions(engine, net)
out.table(yellow, "verbal_yellow_sphere_nbest")
out.table(fig8, "verbal_fig8_descriptions")
fig, (ax,) = plots.new_figure(1, width=7, height=3.6)
plots.plot_nbest(ax, yellow, title=", ".join(f"{k}={v}" for k, v in ex.EVIDENCE_YELLOW_SPHERE.items()))
out.figure(fig, "verbal_yellow_sphere_nbest")
fig8[["evidence", "sentence", "score", "colour_sentence", "colour_score"]]

# %% [markdown]
# ## What a random sample of 10,000 sentences misses

# %%
cmp = ex.sampling_vs_exact(engine, ex.EVIDENCE_AND_BUT["slow"], seeds, n_samples, nbest, grammar)
out.table(cmp, "verbal_sampling_vs_exact")
drawn = sample_sentences(grammar, n_samples, seeds[0])
fig, (ax,) = plots.new_figure(1, width=6, height=3.4)
plots.plot_sampling(ax, all_scores(net, probs), score_sentences(drawn, probs), cmp["exact_score"].iloc[0])
out.figure(fig, "verbal_sampling_vs_exact")
summary = {
    "seeds": len(cmp),
    "best found": int(cmp["found_best"].sum()),
    "mean gap": float(cmp["gap"].mean()),
    "max gap": float(cmp["gap"].max()),
    "median rank of the sample's best": float(np.median(cmp["sample_rank"])),
    "mean overlap of the top lists": float(cmp["overlap"].mean()),
}
summary

# %% [markdown]
# A grasp followed by a still object is described with "but" and one that moved with "and", as in TCDS;
# colour words are rare in the descriptions the network learned from, so the best sentences omit the
# colour and the best one naming it scores lower. The samples above show how often, and by how much in
# score and rank, the originals' 10,000 random sentences miss the best description of the grammar.
