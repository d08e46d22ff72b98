# ---
# jupyter:
#   glu:
#     about: "GLU 2017 Fig. 4 (effect prediction) and Fig. 5 (\u0394p(w)), against the\
#       \ original model"
#     expected_seconds: 3
#     figures:
#     - glu2017_effect_prediction
#     - glu2017_word_change
#     tables:
#     - glu2017_effect_prediction
#     - glu2017_word_change_code
#     - glu2017_word_change_text
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
# # 07 · The figures of GLU 2017
#
# Saponaro et al. (GLU 2017) assume the gesture HMMs recognised a **tap** and enter it as hard evidence in
# the Affordance–Words network. Two results: the object's velocity predicted for a small sphere and for a
# big box (Fig. 4), and how word probabilities change when the tap is added to the evidence (Fig. 5).
# Black ticks mark the authors' own model (`BN_lab.mat`) when the real data is used.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
words: str = "lab"  # descriptions: "lab" (the paper's) or "asr"
unseen_words: str = "zero"  # CPT rows of unseen word parents: "zero" (the original's) or "uniform"
threshold: float = 0.02  # words shown in Fig. 5: |Δp(w)| above this
seed: int = 0  # seed (unused: everything here is exact)
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
from glu.bn import BayesNet, learn_bn
from glu.data import load_experiments
from glu.run import start
from glu.studies.replication import fusion, network_figures
from glu.studies.replication.text import effect_sentence, word_change_sentences

out = start("07_glu2017_figures", globals())
bn = learn_bn(load_experiments(out.source, words), unseen_words=unseen_words)
mat = out.source.original_bn()
original = BayesNet.from_bnt_mat(mat) if mat else None

# %% [markdown]
# ## Fig. 4 · Effect prediction: p(ObjVel | Action=tap, Shape, Size)

# %%
effect = fusion.effect_prediction(bn, original)
out.table(effect, "glu2017_effect_prediction")
out.figure(network_figures.effect_prediction_figure(effect), "glu2017_effect_prediction")
effect

# %% [markdown]
# ## Fig. 5 · Word prediction: Δp(w) = p(w | F, E, A=tap) − p(w | F, E)
# F = {Size=big, Shape=sphere}, E = {ObjVel=fast}. The original code also put Color=yellow in the evidence;
# both versions are computed and compared below. (The paper's text says "rolling"; its figure's word is
# "rolls".)

# %%
changes = fusion.word_probability_changes(bn, original, threshold=threshold)
for variant, change in changes.items():
    out.table(change, f"glu2017_word_change_{variant}", evidence=variant)
out.figure(network_figures.word_change_figure(changes["text"], other=changes["code"]), "glu2017_word_change")
change = changes["code"]
for sentence in [effect_sentence(effect), *word_change_sentences(changes)]:
    out.say("* " + sentence)
change[change.shown][["word", "p_without", "p_with", "delta"]]
