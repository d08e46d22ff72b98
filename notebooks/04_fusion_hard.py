# ---
# jupyter:
#   glu:
#     about: the HMMs' top action as hard evidence, on the five original test gestures
#     expected_seconds: 2
#     figures:
#     - fusion_hard_on_gestures
#     quick:
#       n_iter: 15
#       n_per_action: 6
#     tables:
#     - fusion_hard_on_gestures
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
# # 04 · Hard decision: the HMMs' top action as evidence
#
# The simplest way to join the two models (GLU 2017 §2.4): recognise the gesture, take the most likely
# action, and enter it in the Affordance–Words network as if the robot had seen it for certain. Here the
# gesture HMMs recognise each test gesture, and the network predicts what the gesture will do to a small
# sphere — by the hard decision, and, for comparison, by the two soft rules of notebook 05.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
words: str = "lab"  # descriptions: "lab" (the paper's) or "asr"
unseen_words: str = "zero"  # CPT rows of unseen word parents: "zero" (the original's) or "uniform"
shape: str = "sphere"  # the object the gestures are applied to …
size: str = "small"  # … and its size
n_per_action: int = 20  # synthetic data: training gestures per action
n_iter: int = 200  # synthetic data: most EM iterations of the HMMs
seed: int = 0  # seed of synthetic gestures and EM initialisation
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
from glu.bn import learn_bn
from glu.data import load_experiments
from glu.gestures import gesture_sequences, load_original_models
from glu.gestures.corpus import held_out_gestures
from glu.hmm import TrainingConfig
from glu.run import start
from glu.studies.replication import fusion, fusion_figures, gestures

out = start("04_fusion_hard", globals())
bn = learn_bn(load_experiments(out.source, words), unseen_words=unseen_words)
mat = out.source.original_hmms()
if mat is not None:
    recognizer, models = load_original_models(mat), "original 2013 HMMs"
else:
    sequences = gesture_sequences(out.source, n_per_action, seed)
    recognizer = gestures.train_on(sequences, TrainingConfig(n_iter=n_iter), seed=seed)
    models = "HMMs trained on synthetic gestures"
segments = held_out_gestures(out.source, seed)
print(f"{len(segments)} test gestures, {models}")

# %%
table = fusion.fusion_on_gestures(bn, recognizer, segments, {"Shape": shape, "Size": size})
out.table(table, "fusion_hard_on_gestures", models=models)
out.figure(fusion_figures.fusion_on_gestures_figure(table, value="fast"), "fusion_hard_on_gestures")
table.pivot_table(index=["recording", "start", "hmm_top"], columns=["strategy", "ObjVel"], values="p").round(
    3
)

# %% [markdown]
# When the HMMs recognise the tap, the network predicts the small sphere will roll away fast. A gesture
# the HMMs take for a touch turns the prediction around (the sphere stays still). Over a whole segment the
# HMM posteriors are nearly certain (log-likelihoods differ by tens to hundreds of nats), so soft fusion
# changes little here; it matters while the gesture is still unfolding (notebook 08) and when the models
# disagree less.
