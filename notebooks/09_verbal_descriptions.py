# ---
# jupyter:
#   glu:
#     about: 'sentences from the grammar: TCDS Table II, Fig. 7 and Fig. 8 as printed
#       (the originals'' score and samples) beside the paper''s, the exact N-best under
#       both scores, "and" vs "but", how often random samples miss the best'
#     expected_seconds: 7
#     figures:
#     - verbal_and_but
#     - verbal_sampling_vs_exact
#     - verbal_yellow_sphere_nbest
#     quick:
#       n_trials: 2
#     tables:
#     - verbal_and_but_nbest
#     - verbal_and_but_probabilities
#     - verbal_exact_vs_samples
#     - verbal_published_descriptions
#     - verbal_sampling_vs_exact
#     - verbal_yellow_sphere_nbest
#   jupytext:
#     formats: py:percent
#     notebook_metadata_filter: glu,kernelspec,jupytext,-jupytext.text_representation.format_version,-jupytext.text_representation.jupytext_version
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3 (ipykernel)
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 09 · Verbal descriptions
#
# TCDS 2020 turns the network's word probabilities into sentences: a small grammar (HTK syntax) generates
# descriptions such as "the robot is tapping the ball and the ball is rolling", and the best-scoring ones
# describe the scene. The paper scores a sentence by the mean log probability of its words,
# `(1/L) Σ_k log p(w_k | evidence)`; the originals' code started the sum at 1, so every score it printed is
# `(1 + Σ_k log p(w_k | evidence)) / L` (the `original` score), and it ranked only the distinct sentences of
# 10,000 random draws from the grammar. We first reproduce the printed lists exactly that way, then search
# the whole grammar under each score, and measure how often 10,000 random sentences miss the best one.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
words: str = "lab"  # descriptions: "lab" (the paper's) or "asr"
unseen_words: str = "zero"  # CPT rows of unseen word parents: "zero" (the original's) or "uniform"
nbest: int = 10  # sentences per N-best list
score: str = "original"  # score of the N-best figures: "original" (as printed) or "paper" (the formula)
n_samples: int = 10_000  # random sentences per sample, as the originals
n_trials: int = 20  # random samples drawn per evidence set, to count how often they miss the best
seed: int = 0  # first seed of the random samples
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
import time

from glu.bn import learn_bn, make_engine
from glu.data import load_experiments
from glu.language import (
    candidate_sentences,
    count_sentences,
    default_network,
    load_grammar,
    sample_sentences,
    word_probabilities,
)
from glu.language import nbest as exact_nbest
from glu.run import start
from glu.studies.replication import verbal, verbal_figures
from glu.studies.replication.text import sampling_line, verbal_sentences

out = start("09_verbal_descriptions", globals())
engine = make_engine(learn_bn(load_experiments(out.source, words), unseen_words=unseen_words))
grammar, net = load_grammar(), default_network()
has_samples = out.source.sentence_samples() is not None
samples_label = "the originals' samples" if has_samples else "a stand-in sample"
# the originals' 9,941 sampled sentences come with the real data; elsewhere a seeded sample stands in
samples = (
    candidate_sentences("samples", out.source) if has_samples else sample_sentences(grammar, n_samples, seed)
)
seeds = range(seed, seed + n_trials)
probs = word_probabilities(engine, verbal.EVIDENCE_AND_BUT["medium"])
t0 = time.perf_counter()
exact_nbest(net, probs, nbest, score=score)
print(
    f"grammar: {count_sentences(net):,} sentences of {net.min_length}-{net.max_length} words; "
    f"exact {nbest}-best in {1000 * (time.perf_counter() - t0):.1f} ms; "
    f"candidates: {len(set(samples)):,} sentences, {samples_label}"
)

# %% [markdown]
# ## TCDS Table II, Fig. 7 and Fig. 8, as the paper printed them
# Ranking the originals' sampled sentences with the original score; the paper's sentences and printed scores
# (`glu/resources/published/tcds2020.json`, read once from the authors' LaTeX) beside glu's. `printed` is
# glu's score as the originals' MATLAB printed it. Fig. 8's sentences are, as in the originals' code, the
# best among the sampled sentences that name a colour, not the best of all.

# %%
reproduced = verbal.published_descriptions(engine, samples, score="original")
out.table(
    reproduced,
    "verbal_published_descriptions",
    n_grammar_sentences=count_sentences(net),
    n_candidates=len(set(samples)),
)
scored = reproduced["same_score"].dropna().astype(bool)
print(
    f"{out.source.kind} data, {samples_label}: "
    f"{int(reproduced['same_sentence'].sum())} of {len(reproduced)} published sentences and "
    f"{int(scored.sum())} of {len(scored)} printed scores reproduced"
)
reproduced[["figure", "rank", "paper_sentence", "paper_score", "sentence", "printed", "same_sentence"]]

# %% [markdown]
# ## "and" or "but": a grasp, then the object moves or stays still (Fig. 7)

# %%
and_but = verbal.and_but_probabilities(engine, compare=out.source.is_real)
lists = verbal.and_but_nbest(engine, nbest, score=score, candidates=samples)
out.table(and_but, "verbal_and_but_probabilities", reference="TCDS 2020 Fig. 7 bars (published EPS)")
out.table(lists, "verbal_and_but_nbest")
fig = verbal_figures.and_but_figure(and_but, lists, score=score)
out.figure(fig, "verbal_and_but")
and_but

# %% [markdown]
# ## The big yellow sphere that moved fast (Table II)

# %%
yellow = verbal.yellow_sphere_nbest(engine, nbest, net, score=score, candidates=samples)
out.table(yellow, "verbal_yellow_sphere_nbest")
fig = verbal_figures.nbest_figure(yellow, verbal.EVIDENCE_YELLOW_SPHERE, score, "the samples")
out.figure(fig, "verbal_yellow_sphere_nbest")

# %% [markdown]
# ## What the exact search over the whole grammar finds, under each score
# For each published evidence set: the best sentence of the grammar, the best of the samples, the rank of
# the samples' best among all sentences of the grammar, and the rank of each score's best under the other
# score. The `+1/L` of the original score favours short sentences, so the two scores need not agree.

# %%
versus = verbal.exact_vs_samples(engine, samples, grammar)
out.table(versus, "verbal_exact_vs_samples")
versus.drop(columns=["evidence"])

# %% [markdown]
# ## How often 10,000 random sentences miss the best of the grammar
# Each trial draws `n_samples` random sentences (seeded) as the originals did and keeps the best under the
# original score. `p_draw_best` is the exact probability that such a sample contains the grammar's best.

# %%
trials = verbal.sampling_trials(
    engine, seeds, verbal.PUBLISHED_LISTS, n_samples, nbest, grammar, score="original"
)
out.table(trials, "verbal_sampling_vs_exact", n_trials=len(trials), n_found=int(trials["found_best"].sum()))
example = verbal.sampling_example(engine, trials, net, grammar, "fig7a", score="original")
out.figure(verbal_figures.sampling_figure(example), "verbal_sampling_vs_exact")
print(sampling_line(trials))
verbal.trials_per_set(trials)

# %%
for sentence in verbal_sentences(reproduced, and_but, versus, trials):
    out.say("* " + sentence)
