# ---
# jupyter:
#   glu:
#     about: K2 + BIC structure and BDeu/ML parameters, the original's all-zero rows
#       and what they change
#     expected_seconds: 3
#     figures:
#     - bn_structure
#     - unseen_rows_comparison
#     tables:
#     - bn_learning_summary
#     - bn_structure
#     - unseen_rows_comparison
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
# # 03 · Learning the Affordance–Words network
#
# The robot explored objects on its own: 1270 experiments, each an action (grasp, tap, touch) on an object
# (Color, Shape, Size) with its effects (ObjVel, ObjHandVel, HandVel, Contact) and a spoken description.
# From them the original learned a Bayesian network (Salvi et al. 2012): K2 search with BIC over the
# affordance nodes in a fixed order, then each word's parents among the affordance nodes; BDeu parameters
# for affordance nodes, maximum likelihood for words. We learn it the same way and compare with the
# authors' model, `BN_lab.mat`.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
words: str = "lab"  # descriptions: "lab" (transcribed, the paper's) or "asr" (speech recogniser)
seed: int = 0  # seed (learning itself is deterministic)
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
import time

from glu.bn import BayesNet, learn_bn
from glu.data import load_experiments
from glu.run import start
from glu.studies.replication import fusion, network_figures

out = start("03_bn_learning", globals())
table = load_experiments(out.source, words)
t0 = time.perf_counter()
bn = learn_bn(table)
print(f"learned {len(bn.edges())} edges from {len(table)} experiments in {time.perf_counter() - t0:.3f} s")

# %% [markdown]
# ## The structure, next to the original's
# With the real data the reference is the authors' model; with synthetic data it is the generator's own
# structure, which learning should recover.

# %%
mat = out.source.original_bn()
original = BayesNet.from_bnt_mat(mat) if mat else None
edges = fusion.structure_comparison(bn, original)
out.table(edges, reference=edges.attrs["parameters"]["reference"])
print(
    f"edges: ours {int(edges.in_ours.sum())}, reference {int(edges.in_reference.sum())}, differing "
    f"{int(edges.difference.sum())}"
)

out.figure(network_figures.structure_figure(bn, original), "bn_structure")

# %% [markdown]
# ## The CPTs, and the original's quirk
# A word's parent configuration never seen in training has 0/0 counts; the original left that CPT row all
# zeros, which removes those affordance configurations from every query. glu reproduces it by default
# (`unseen_words="zero"`) and offers uniform rows; here is how much the published numbers move.

# %%
numbers = fusion.network_summary(bn, table, original)
out.table(numbers, "bn_learning_summary")
print(f"zero rows: {bn.zero_rows()}")
uniform = learn_bn(table, unseen_words="uniform")
comparison = fusion.unseen_rows_comparison(bn, uniform)
out.table(comparison, "unseen_rows_comparison")
print(f"uniform rows move these numbers by up to {comparison.uniform_minus_zero.abs().max():.2f}")
print(numbers.to_string(index=False))
out.figure(network_figures.unseen_rows_figure(comparison), "unseen_rows_comparison")
comparison.loc[comparison.uniform_minus_zero.abs().sort_values(ascending=False).index[:5]]

# %% [markdown]
# Learning reproduces the original network exactly on the real data (the structure, every CPT and the
# log-likelihood of the data, in the table above), and the all-zero rows matter: they change the
# word-probability differences of GLU 2017 Fig. 5 (by the amount printed above).

# %% [markdown]
# ## Try it: query the learned network
# Choose values of the affordance nodes and watch the network's beliefs about the effect, the action and
# the words it would use (interactive when run live in JupyterLab, `make lab`; a table here otherwise).

# %%
from glu.bn import make_engine
from glu.explorer import evidence_explorer

evidence_explorer(make_engine(bn), evidence={"Action": "tap", "Shape": "sphere"})
