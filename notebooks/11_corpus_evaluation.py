# ---
# jupyter:
#   glu:
#     about: 'every fusion strategy on 20,000 simulated episodes, with 95 % intervals:
#       accuracy and calibration against noise, early recognition, viewpoints, paired
#       differences (the sweep of `glu evaluate`, in-process; `-p workers 2` on Dask)'
#     expected_seconds: 22
#     figures:
#     - corpus_calibration
#     - corpus_differences
#     - corpus_early_recognition
#     - corpus_strategies_vs_noise
#     quick:
#       bootstrap: 40
#       chunk_size: 60
#       episodes: 240
#       fractions:
#       - 0.4
#       - 1.0
#       n_iter: 10
#       n_mix: 1
#       n_per_action: 6
#       n_states: 3
#       noise_levels:
#       - 0.0
#       - 0.05
#       viewpoints:
#       - front
#       - seated
#       workers: 0
#     tables:
#     - corpus_differences
#     - corpus_metrics
#     - corpus_reliability
#   jupytext:
#     formats: py:percent
#     notebook_metadata_filter: glu,kernelspec,jupytext,-jupytext.text_representation.format_version,-jupytext.text_representation.jupytext_version
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 11 · Every fusion strategy, measured on a large simulated corpus
#
# The papers illustrate fusion on five real segments; their future work asks for quantitative tests on
# larger corpora. Here glu simulates episodes — an object and a person's action from a scenario, the effect
# and the words drawn from the Affordance–Words network, the person's hand from the gesture generator under
# sensor noise and from several viewpoints — and measures, with bootstrap intervals, what each strategy
# gets right: the action (after seeing the effect), the effect before it happens (anticipation), and the
# best verbal description; as the noise grows, as more of the gesture is seen, and how well calibrated the
# predictions are. It is the sweep `glu evaluate` runs as Dask tasks; at this size it runs in this process:
# on 2 cores a LocalCluster of 2 workers is no faster here, and under `glu reproduce` its workers would compete
# with the other notebook for the cores. `-p workers 2` runs it on a cluster, which pays off for larger corpora
# (the README's speed table).

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
episodes: int = 20000  # simulated episodes in all, shared by the noise × viewpoint conditions
noise_levels: list[float] = [0.0, 0.02, 0.05, 0.1]  # sensor noise on every joint (m)
viewpoints: list[str] = ["front", "turned", "seated"]  # how the robot sees the person (corpus.VIEWPOINTS)
posteriors: list[str] = ["likelihood", "per_frame"]  # how p_HMM is read from the HMMs (corpus.POSTERIORS)
fractions: list[float] = [0.2, 0.4, 0.6, 0.8, 1.0]  # observed fractions of each gesture
bootstrap: int = 200  # Poisson bootstrap replicates for the 95 % intervals
chunk_size: int = 2000  # episodes per task
n_per_action: int = 20  # recogniser: synthetic training gestures per action
n_states: int = 6  # recogniser: HMM states per action
n_mix: int = 3  # recogniser: Gaussians per state
n_iter: int = 200  # recogniser: most EM iterations
workers: int = 0  # 0: run the chunks in this process; N: on a Dask LocalCluster of N workers
seed: int = 0  # seed of the corpus, the recogniser's training gestures and EM
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
import tempfile

from glu import plots
from glu.run import start
from glu.sweep import config_from_dict, run_sweep

out = start("11_corpus_evaluation", globals())
settings = {
    "episodes": episodes,
    "seed": seed,
    "chunk_size": chunk_size,
    "grid": {
        "noise": noise_levels,
        "viewpoints": viewpoints,
        "posteriors": posteriors,
        "fractions": fractions,
    },
    "network": {"data": "synthetic" if out.source.root is None else str(out.source.root)},
    "evaluation": {"bootstrap": bootstrap},
    "recognizer": {"n_per_action": n_per_action, "n_states": n_states, "n_mix": n_mix, "n_iter": n_iter},
}
config = config_from_dict(settings)

# %% [markdown]
# ## The sweep
#
# One task per chunk of episodes and condition; every episode is scored at every observed fraction by
# every strategy. Here the chunks go to a temporary folder; `glu evaluate -o DIR` keeps them, so an
# interrupted sweep resumes where it stopped.

# %%
with tempfile.TemporaryDirectory() as sweep_dir:
    result = run_sweep(
        config,
        sweep_dir,
        scheduler=None if workers else "synchronous",
        workers=workers or None,
        progress=False,
    )
table, diffs, rel = result.metrics, result.differences, result.reliability
pooled = table[(table.viewpoint == "all") | table.noise.isna()]
out.table(pooled, "corpus_metrics", episodes=result.summary["episodes"])
out.table(diffs[diffs.noise.isna()], "corpus_differences")
out.table(rel[rel.noise.isna()], "corpus_reliability")
full = max(config.evaluation.fractions)
overall = table[(table.viewpoint == "all") & table.noise.isna() & (table.fraction == full)]
overall.pivot_table(
    index=["posterior", "target", "metric"], columns="strategy", values="estimate", sort=False
).round(3)

# %% [markdown]
# ## Which strategy wins as the sensor noise grows
#
# Left, p_HMM as the originals read it from the likelihoods; right, per frame (`posteriors`). Every band is a
# bootstrap interval (`glu.experiments.intervals.LEVEL`).

# %%
fig = plots.strategies_vs_noise_figure(table, posteriors[:2], full)
out.figure(fig, "corpus_strategies_vs_noise", source=result.summary["data_source"])

# %% [markdown]
# ## Early recognition: how much of the gesture is needed

# %%
fig = plots.early_recognition_figure(table, posteriors[:2])
out.figure(fig, "corpus_early_recognition", source=result.summary["data_source"])

# %% [markdown]
# ## Calibration of the anticipated effect, and the viewpoints

# %%
fig = plots.calibration_figure(rel, table, posteriors, full)
out.figure(fig, "corpus_calibration", source=result.summary["data_source"])

# %% [markdown]
# ## Paired differences between strategies (same episodes)

# %%
pairs = [
    ("action", "accuracy", "product", "gesture"),
    ("action", "log_loss", "product", "gesture"),
    ("action", "accuracy", "hard", "gesture"),
    ("effect", "accuracy", "virtual", "network"),
    ("effect", "log_loss", "virtual", "hard"),
    ("effect", "log_loss", "jeffrey", "virtual"),
    ("effect", "ece", "virtual", "hard"),
    ("description", "all", "virtual", "hard"),
    ("description", "all", "jeffrey", "virtual"),
]
fig = plots.differences_figure(diffs, pairs, posteriors[:2], full)
out.figure(fig, "corpus_differences", source=result.summary["data_source"])
lines = [
    f"p_HMM {b['posterior']}, {b['target']} {b['metric']}: {', '.join(b['best'])} {b['estimate']:.3f} "
    f"[{b['ci_low']:.3f}, {b['ci_high']:.3f}], better than {', '.join(b['significantly_better_than']) or 'none'}"
    for b in result.summary["best"]
]
print("\n".join(lines))

# %% [markdown]
# Read from the likelihoods (as the originals), the HMMs' posteriors are nearly certain after a few dozen
# frames, right or wrong — their log-loss is several nats: fusion then changes little, and a hard decision
# is as good as any soft rule. Read per frame, p_HMM keeps some honest doubt and soft fusion pays: the
# product rule names the action more often than the gesture alone (most clearly early in the gesture, under
# strong noise, and for the viewpoints the HMMs were not trained on), and soft evidence — Jeffrey's rule
# most of all — anticipates the effect with a lower log-loss and a smaller calibration error than a hard
# decision. Seen from a turned viewpoint the gestures mislead more than they help: the network alone is then
# more accurate, the correspondence problem of notebook 10. The lines above name, for each target and metric,
# the best strategy and those it beats with confidence; every number with its interval is in
# `results/corpus_metrics.csv`.
