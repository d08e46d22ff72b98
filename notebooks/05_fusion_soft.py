# ---
# jupyter:
#   glu:
#     about: 'soft evidence: virtual (the originals'') vs Jeffrey''s rule, on the TCDS
#       rows and a continuous sweep'
#     expected_seconds: 3
#     figures:
#     - fusion_soft_rules
#     - fusion_soft_sweep
#     quick:
#       n_points: 11
#     tables:
#     - fusion_soft_rules
#     - fusion_soft_sweep_box
#     - fusion_soft_sweep_sphere
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
# # 05 · Soft fusion: virtual evidence or Jeffrey's rule
#
# A gesture HMM rarely is certain. TCDS passes its whole posterior `p_HMM(A | G)` to the network as soft
# evidence on Action. The originals enter it as *virtual (likelihood) evidence* — the BN's own belief about
# the action is multiplied by the HMM's — while the literature they cite also defines soft evidence by
# *Jeffrey's rule*, which sets the Action marginal to `p_HMM` exactly. Here both, side by side, on the TCDS
# effect-prediction experiment and on a continuous sweep of `p_HMM(tap)`.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
words: str = "lab"  # descriptions: "lab" (the paper's) or "asr"
unseen_words: str = "zero"  # CPT rows of unseen word parents: "zero" (the original's) or "uniform"
n_points: int = 101  # points of the p_HMM(tap) sweep
seed: int = 0  # seed (unused: everything here is exact)
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
from glu.bn import BayesNet, learn_bn
from glu.data import load_experiments
from glu.run import start
from glu.studies.replication import fusion, fusion_figures, network_figures

out = start("05_fusion_soft", globals())
bn = learn_bn(load_experiments(out.source, words), unseen_words=unseen_words)

# %% [markdown]
# ## TCDS effect prediction with both rules
# p_comb(ObjVel | Shape) for the TCDS rows of p_HMM [grasp, tap, touch].

# %%
mat = out.source.original_bn()
original = BayesNet.from_bnt_mat(mat) if mat else None
table = fusion.effect_vs_soft_evidence(bn, rules=("virtual", "jeffrey"), reference=original)
out.table(table, "fusion_soft_rules")
out.figure(network_figures.effect_vs_rules_figure(table), "fusion_soft_rules")

# %% [markdown]
# ## A continuous sweep of p_HMM(tap)

# %%
sweeps = fusion.soft_evidence_sweeps(bn, n_points=n_points)
for shape, sweep in sweeps.items():
    out.table(sweep, f"fusion_soft_sweep_{shape}")
out.figure(fusion_figures.soft_sweep_figure(sweeps), "fusion_soft_sweep")
pivot = sweeps["box"].pivot_table(index="p_hmm_tap", columns=["rule", "ObjVel"], values="p")
pivot.iloc[:: max(1, len(pivot) // 5)]

# %% [markdown]
# The two rules agree at the ends (no doubt about the action) and differ in between: virtual evidence lets
# the network's own knowledge of which actions move a sphere pull the belief, while Jeffrey's rule trusts
# the HMM's numbers as they are and mixes the action-conditional predictions linearly.

# %% [markdown]
# ## Try it: an evidence explorer
# Set the object's features and effects, give the gesture recogniser's belief p_HMM(Action), pick the rule,
# and watch p_comb(ObjVel), p_comb(Action) and the best descriptions change. Run live in JupyterLab
# (`make lab`) it is interactive; in the executed notebook it shows the starting point below.

# %%
from glu.bn import make_engine
from glu.explorer import evidence_explorer

evidence_explorer(make_engine(bn), evidence={"Shape": "sphere", "Size": "small"}, p_hmm=[0.2, 0.6, 0.2])
