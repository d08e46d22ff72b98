# ---
# jupyter:
#   glu:
#     about: 'every fusion strategy on simulated episodes, a factorial design built to
#       fail: action prior × inference network (generating or learned) × p_HMM reading,
#       over recogniser seeds, with two-level intervals; the network alone and the true
#       action beside the rules; p_HMM''s own calibration, synthetic and real'
#     expected_seconds: 30
#     figures:
#     - corpus_calibration
#     - corpus_differences
#     - corpus_early_recognition
#     - corpus_p_hmm_calibration
#     - corpus_strategies_vs_noise
#     - corpus_winners
#     quick:
#       bootstrap: 40
#       calibration_per_action: 3
#       episodes: 240
#       fractions:
#       - 0.4
#       - 1.0
#       learn_experiments:
#       - 100
#       n_iter: 10
#       n_per_action: 6
#       n_states: 3
#       noise_levels:
#       - 0.0
#       - 0.05
#       recognizer_seeds: 2
#       viewpoints:
#       - front
#       - turned
#     real_only:
#     - p_hmm_real_calibration
#     - p_hmm_real_segments
#     tables:
#     - corpus_calibration
#     - corpus_differences
#     - corpus_findings
#     - corpus_metrics
#     - corpus_reliability
#     - corpus_seeds
#     - corpus_winners
#     - p_hmm_real_calibration
#     - p_hmm_real_segments
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
# # 11 · Every fusion strategy on a simulated corpus, in a design that can fail
#
# The papers illustrate fusion on five real segments; their future work asks for quantitative tests on
# larger corpora. Here glu simulates episodes — an object and a person's action, the effect and the words
# drawn from an Affordance–Words network, the hand from the gesture generator under sensor noise and from
# several viewpoints — and measures what each strategy gets right: the action (after seeing the effect),
# the effect before it happens (anticipation), the best verbal description.
#
# **What the simulation assumes.** The effects and words are drawn from a network, and the gestures from
# the very generator the HMMs are trained on. If the robot infers with that same network, the comparison
# only says how the rules behave under a correct model. So the design crosses three ways of being wrong:
# how often each action is performed (`action_prior`: uniformly, or as the network's prior says), which
# network the robot infers with (`inference_network`: the generating one, or one glu learned by K2 + BIC
# from a simulated experiment table of `learn_experiments` rows — the robot's own limited experience),
# and how it reads p_HMM (`p_hmm`: from the likelihoods as the originals, per frame, or calibrated by a
# temperature fitted on held-out training gestures). Every recogniser seed is a replication with its own
# recogniser, learned networks and episodes; every interval is a two-level bootstrap over the seeds and the
# episodes within each, and a paired difference whose interval contains 0 counts as no difference. The
# network alone and the true action (an oracle) stand beside the fusion rules. `docs/corpus-evaluation.md`
# describes the design; the full grid runs with `glu evaluate --config` on Dask, and `sweep_dir` reads its
# tables here.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
sweep_dir: str = None  # a finished `glu evaluate -o DIR` folder: show its tables instead of running a sweep
episodes: int = 7200  # simulated episodes in all, shared by the conditions and the recogniser seeds
recognizer_seeds: int = 10  # replications: each its own recogniser, learned networks and episodes
action_prior: list[str] = ["uniform", "network"]  # how often each action is performed
inference_network: list[str] = ["generating", "learned"]  # the network the robot infers with
learn_experiments: list[int] = [100, 1270]  # rows of the experiment tables the learned networks see
p_hmm: list[str] = ["likelihood", "per-frame", "calibrated"]  # how p_HMM is read from the HMMs
noise_levels: list[float] = [0.0, 0.05]  # sensor noise on every joint (m)
viewpoints: list[str] = ["front", "turned"]  # how the robot sees the person (corpus.VIEWPOINTS)
fractions: list[float] = [0.2, 0.6, 1.0]  # observed fractions of each gesture
bootstrap: int = 200  # two-level bootstrap replicates for the 95 % intervals
chunk_size: int = 2000  # episodes per recogniser seed in one task
n_per_action: int = 10  # recogniser: synthetic training gestures per action
calibration_per_action: int = 10  # recogniser: held-out gestures the calibrated reading is fitted on
n_states: int = 6  # recogniser: HMM states per action
n_mix: int = 1  # recogniser: Gaussians per state
n_iter: int = 50  # recogniser: most EM iterations
workers: int = 0  # 0: run the chunks in this process; N: on a Dask LocalCluster of N workers
seed: int = 0  # seed of the corpus, the recognisers, their calibration and the learned networks
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
import tempfile

import matplotlib.pyplot as plt

from glu.gestures.corpus import gesture_sequences
from glu.run import start
from glu.studies.corpus_evaluation import figures, findings, p_hmm_readings
from glu.studies.corpus_evaluation.config import config_from_dict
from glu.studies.corpus_evaluation.sweep import run_sweep
from glu.studies.corpus_evaluation.tables import read_tables

out = start("11_corpus_evaluation", globals())
if sweep_dir is None:
    config = config_from_dict(
        {
            "episodes": episodes,
            "seed": seed,
            "chunk_size": chunk_size,
            "recognizer_seeds": recognizer_seeds,
            "grid": {
                "action_prior": action_prior,
                "inference_network": inference_network,
                "learn_experiments": learn_experiments,
                "p_hmm": p_hmm,
                "noise": noise_levels,
                "viewpoints": viewpoints,
                "fractions": fractions,
            },
            "network": {"data": "synthetic" if out.source.root is None else str(out.source.root)},
            "evaluation": {"bootstrap": bootstrap},
            "recognizer": {
                "n_per_action": n_per_action,
                "n_states": n_states,
                "n_mix": n_mix,
                "n_iter": n_iter,
                "calibration_per_action": calibration_per_action,
            },
        }
    )
    with tempfile.TemporaryDirectory() as folder:
        run_sweep(
            config,
            folder,
            scheduler=None if workers else "synchronous",
            workers=workers or None,
            progress=False,
        )
        table, diffs, rel, seeds, calibration, summary = read_tables(folder)
else:
    table, diffs, rel, seeds, calibration, summary = read_tables(sweep_dir)
source = summary["data_source"]
pooled = table[(table.viewpoint == "all") | table.noise.isna()]
out.table(pooled, "corpus_metrics", episodes=summary["episodes"])
out.table(diffs[diffs.noise.isna() & (diffs.viewpoint == "all")], "corpus_differences")
out.table(rel[rel.noise.isna()], "corpus_reliability")
out.table(seeds[seeds.fraction == seeds.fraction.max()], "corpus_seeds")
out.table(calibration, "corpus_calibration")
out.say(findings.design_text(summary))

# %% [markdown]
# ## Which strategy wins in which cell
# Each cell names the best strategy at the full gesture (pooled over noise levels and viewpoints) and, after
# `=`, the initials of those with no difference from it (G gesture, N network, H hard, V virtual, J Jeffrey,
# P product; the true action, an oracle, left out).

# %%
win = findings.winners(table, diffs)
out.table(win, "corpus_winners")
shown = [("action", "accuracy"), ("effect", "log_loss"), ("effect", "ece"), ("description", "all")]
rows = win.groupby(list(findings.DESIGN[:3])).ngroups
fig, axes = plt.subplots(2, 2, figsize=(10, 0.9 * rows + 2.5))
for ax, (target, metric) in zip(axes.ravel(), shown, strict=True):
    figures.plot_winners(ax, win, target, metric)
out.figure(fig, "corpus_winners", source=source)
findings.winners_table(win, shown)

# %% [markdown]
# ## The earlier findings, followed through the design
# Each claim is a paired difference between two strategies; its verdict in every cell, and a sentence per
# claim written from them.

# %%
verdicts = findings.finding_verdicts(diffs)
out.table(verdicts, "corpus_findings")
for sentence in findings.finding_sentences(verdicts):
    out.say("* " + sentence)

# %% [markdown]
# ## Against the sensor noise, early in the gesture, and how well calibrated
# The reference cell (uniform actions, the generating network, p_HMM per frame) beside the most mismatched
# one; bands are two-level intervals.

# %%
cells = findings.contrast_cells(table)
full = table.fraction.max()
out.figure(
    figures.strategies_vs_noise_figure(table, cells, full),
    "corpus_strategies_vs_noise",
    source=source,
    caption="Action accuracy (top) and the effect's log-loss (bottom) against the sensor noise, one column "
    "per cell.",
)
out.figure(
    figures.early_recognition_figure(table, cells),
    "corpus_early_recognition",
    source=source,
    caption="The same against the fraction of the gesture seen: how early each strategy knows.",
)
out.figure(
    figures.calibration_figure(rel, table, cells, full),
    "corpus_calibration",
    source=source,
    caption="Reliability of the predicted effect in both cells (top; a marker's size is its bin's share of "
    "the episodes); the effect's calibration error against the noise (bands) and the action accuracy per "
    "viewpoint (error bars) in the reference cell (bottom).",
)
for line in findings.network_alone_sentences(table):
    out.say("* " + line)

# %% [markdown]
# ## Paired differences, in the reference cell and the most mismatched one
# Each finding as the paired difference between a strategy and its baseline on the same episodes, with its
# paired bootstrap interval; a filled marker where the interval excludes zero on the better side.

# %%
pairs = [
    (f.target, f.metric, f.strategy, f.baseline) for f in findings.FINDINGS if f.viewpoint == "all" and not f.early
]
out.figure(figures.differences_figure(diffs, pairs, cells, full), "corpus_differences", source=source)

# %% [markdown]
# ## Is p_HMM a probability?
# Left: p_HMM's own reliability on the corpus's held-out synthetic gestures, under each reading (the
# reference cell's actions and network). Right, with the real data: each real standing segment left out,
# recognised by HMMs trained on the others; the calibrated reading's temperature is fitted on the other
# segments only, each scored by models that saw neither.

# %%
real = out.source.is_real
segments = None
if real:
    segments = p_hmm_readings.segment_readings(gesture_sequences(out.source, include_test=False), seed=seed)
    out.table(segments, "p_hmm_real_segments")
    segment_summary = p_hmm_readings.segment_calibration(segments)
    out.table(segment_summary, "p_hmm_real_calibration")
cell = {k: v for k, v in findings.REFERENCE_CELL.items() if k != "p_hmm"}
fig = figures.p_hmm_calibration_figure(rel, full, where=cell, segments=segments)
out.figure(fig, "corpus_p_hmm_calibration", source=source)
for line in findings.p_hmm_sentences(table, calibration, segment_summary if real else None):
    out.say("* " + line)
segment_summary if real else findings.p_hmm_table(table)

# %% [markdown]
# ## How much the recogniser's seed moves the result
# Each seed's own accuracy at the full gesture (reference cell); the seed level of every interval above
# carries this spread.

# %%
spread = findings.seed_spread(seeds)
out.say(findings.seed_sentence(spread))
spread
