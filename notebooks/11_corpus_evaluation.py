# ---
# jupyter:
#   jupytext:
#     formats: py:percent
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
# sensor noise and from several viewpoints — and measures, with 95 % bootstrap intervals, what each strategy
# gets right: the action (after seeing the effect), the effect before it happens (anticipation), and the
# best verbal description; as the noise grows, as more of the gesture is seen, and how well calibrated the
# predictions are. The sweep runs as Dask tasks (`glu evaluate` runs the same sweep from the command line).

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
episodes: int = 20000  # simulated episodes in all, shared by the noise × viewpoint conditions
noise_levels: list[float] = [0.0, 0.02, 0.05, 0.1]  # sensor noise on every joint (m)
viewpoints: list[str] = ["front", "turned", "seated"]  # how the robot sees the person (glu.experiments.corpus.VIEWPOINTS)
fractions: list[float] = [0.2, 0.4, 0.6, 0.8, 1.0]  # observed fractions of each gesture
bootstrap: int = 200  # Poisson bootstrap replicates for the 95 % intervals
workers: int = 2  # Dask LocalCluster workers; 0: run the chunks in this process
seed: int = 0  # seed of the corpus, the recogniser's training gestures and EM
quick: bool = False  # small, fast run (for tests)
out_dir: str = None  # folder for figures/, results/; None: the project's own

# %%
import tempfile

from glu import plots
from glu.outputs import open_outputs
from glu.sweep import config_from_dict, run_sweep

out = open_outputs("11_corpus_evaluation", data, out_dir)
settings = {
    "episodes": episodes, "seed": seed, "chunk_size": 2000,
    "grid": {"noise": noise_levels, "viewpoints": viewpoints, "fractions": fractions},
    "network": {"data": "synthetic" if out.source.root is None else str(out.source.root)},
    "evaluation": {"bootstrap": bootstrap},
}  # fmt: skip
if quick:
    settings.update(episodes=240, chunk_size=60, evaluation={"bootstrap": 40})
    settings["grid"].update(noise=[0.0, 0.05], viewpoints=["front", "seated"], fractions=[0.4, 1.0])
    settings["recognizer"] = {"n_per_action": 6, "n_states": 3, "n_mix": 1, "n_iter": 10}
    workers = 0
config = config_from_dict(settings)

# %% [markdown]
# ## The sweep
#
# One task per chunk of episodes and condition; every episode is scored at every observed fraction by
# every strategy. Finished chunks are kept, so an interrupted run resumes where it stopped.

# %%
with tempfile.TemporaryDirectory() as sweep_dir:
    result = run_sweep(config, sweep_dir, scheduler=None if workers else "synchronous", workers=workers or None,
                       progress=False)  # fmt: skip
table, diffs, rel = result.metrics, result.differences, result.reliability
pooled = table[(table.viewpoint == "all") | table.noise.isna()]
out.table(pooled, "corpus_metrics", episodes=result.summary["episodes"])
out.table(diffs[diffs.noise.isna()], "corpus_differences")
out.table(rel[rel.noise.isna()], "corpus_reliability")
full = max(config.evaluation.fractions)
overall = table[(table.viewpoint == "all") & table.noise.isna() & (table.fraction == full)]
overall.pivot_table(index=["target", "metric"], columns="strategy", values="estimate", sort=False).round(3)

# %% [markdown]
# ## Which strategy wins as the sensor noise grows

# %%
fig, axes = plots.new_figure(3, width=4.0)
plots.plot_metric_vs_noise(axes[0], table, "action", "accuracy", full)
plots.plot_metric_vs_noise(axes[1], table, "effect", "log_loss", full)
plots.plot_metric_vs_noise(axes[2], table, "description", "all", full)
axes[0].legend(fontsize=7)
out.figure(fig, "corpus_strategies_vs_noise", source=result.summary["data_source"])

# %% [markdown]
# ## Early recognition: how much of the gesture is needed

# %%
fig, axes = plots.new_figure(2, width=4.4)
plots.plot_early_recognition(axes[0], table, "action", "accuracy")
plots.plot_early_recognition(axes[1], table, "effect", "accuracy")
axes[0].legend(fontsize=7)
out.figure(fig, "corpus_early_recognition", source=result.summary["data_source"])

# %% [markdown]
# ## Calibration of the anticipated effect, and the viewpoints

# %%
fig, axes = plots.new_figure(3, width=4.0)
plots.plot_reliability(axes[0], rel, full, strategies=["network", "hard", "virtual", "jeffrey", "true_action"])
plots.plot_metric_vs_noise(axes[1], table, "effect", "ece", full)
plots.plot_by_viewpoint(axes[2], table, "action", "accuracy", full, strategies=["gesture", "hard", "virtual", "product"])
axes[0].legend(fontsize=7)
out.figure(fig, "corpus_calibration", source=result.summary["data_source"])

# %% [markdown]
# ## Paired differences between strategies (same episodes)

# %%
pairs = [
    ("action", "accuracy", "product", "gesture"), ("action", "log_loss", "product", "gesture"),
    ("action", "accuracy", "hard", "gesture"), ("effect", "accuracy", "virtual", "network"),
    ("effect", "log_loss", "virtual", "hard"), ("effect", "log_loss", "jeffrey", "virtual"),
    ("effect", "ece", "virtual", "hard"), ("description", "all", "virtual", "hard"),
    ("description", "all", "jeffrey", "virtual"),
]  # fmt: skip
fig, (ax,) = plots.new_figure(1, width=7.5, height=3.6)
plots.plot_differences(ax, diffs, pairs, full)
out.figure(fig, "corpus_differences", source=result.summary["data_source"])
best = {(b["target"], b["metric"]): b for b in result.summary["best"]}
lines = [f"{t} {m}: {b['best']} {b['estimate']:.3f} [{b['ci_low']:.3f}, {b['ci_high']:.3f}], better than "
         f"{', '.join(b['significantly_better_than']) or 'none significantly'}" for (t, m), b in best.items()]  # fmt: skip
print("\n".join(lines))

# %% [markdown]
# Fusing the gesture with the network's knowledge of the object and its motion (the product rule, which is
# virtual evidence for the action) names the action more often than the gestures alone, and the gap widens
# with the sensor noise and for the viewpoints the HMMs were not trained on. The HMMs' posteriors are
# over-confident — their log-loss is far above their error rate would suggest — and a hard decision makes it
# worse; soft evidence keeps their doubt and gives the best calibrated effect predictions short of knowing
# the true action. Virtual evidence and Jeffrey's rule differ little on these scenes: they part ways only
# where the network's own belief about the action is far from uniform. The numbers behind every curve, with
# their intervals, are in `results/corpus_metrics.csv`.
