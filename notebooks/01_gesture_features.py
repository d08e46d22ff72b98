# ---
# jupyter:
#   glu:
#     about: hand trajectories, tracking gaps and outliers, automatic segmentation into
#       repetitions
#     expected_seconds: 3
#     figures:
#     - gesture_segmentation
#     tables:
#     - gesture_segments
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
# # 01 · Hand trajectories and gesture features
#
# A depth sensor tracks the person's skeleton; the features are the right hand relative to the torso,
# x and z divided by the shoulder distance and y by the neck–torso distance (x to the person's right, y up,
# z towards their back). The recordings of 2017 log these features directly. Real tracking drops out and
# jumps: glu detects gaps and outliers, repairs short ones and splits at long ones, then cuts each
# recording into gesture repetitions from the hand's activity (distance from the rest pose and speed).
# With the real data the originals' hand-cut test segments are shown as black bars; with synthetic data,
# the true repetitions.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
seed: int = 0  # seed of the synthetic recordings
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
from glu.gestures.corpus import recording_segmentations
from glu.run import start
from glu.studies.replication import gesture_figures, gestures

out = start("01_gesture_features", globals())
segmentations = recording_segmentations(out.source, seed=seed)
table = gestures.segmentation_table(segmentations, out.data_label)
out.table(table, "gesture_segments")

# %%
out.figure(gesture_figures.segmentation_figure(segmentations), "gesture_segmentation")
table.groupby("recording", sort=False).agg(
    segments=("segment", "max"),
    reference=("n_reference", "first"),
    gaps=("n_gaps", "first"),
    spikes=("n_spikes", "first"),
)

# %% [markdown]
# Each training recording yields one segment per repetition (push1_hand loses a repetition to a long
# tracking gap, where the trajectory is split); the single-tap recordings yield one segment each, around
# the originals' hand-cut ranges. These segments train the gesture HMMs in notebook 02.
