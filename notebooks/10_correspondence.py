# ---
# jupyter:
#   glu:
#     about: 'the correspondence problem: HMMs trained on the robot''s own movements
#       or one human view, recognising people turned, mirrored, seated, bigger or smaller,
#       with raw and invariant features; the real seated taps over feature sets, EM
#       settings and seeds (+ 1 Rerun recording)'
#     expected_seconds: 20
#     figures:
#     - correspondence_conditions
#     - correspondence_invariance_effects
#     - correspondence_two_views
#     - correspondence_viewpoint
#     - hmm_feature_settings
#     quick:
#       feature_sets:
#       - raw
#       - centred
#       - all
#       levels:
#       - "0\xB0"
#       - "90\xB0"
#       - mirrored
#       n_iter: 10
#       n_mix: 1
#       n_states: 3
#       n_test: 2
#       n_train: 3
#       real_features:
#       - raw
#       - centred
#       real_n_iter: 10
#       real_seeds:
#       - 0
#       real_settings:
#       - Q3 M1
#       seeds:
#       - 0
#       - 1
#     real_only:
#     - hmm_feature_settings
#     - hmm_feature_settings_summary
#     recordings:
#     - correspondence_two_views
#     tables:
#     - correspondence_invariance_effects
#     - correspondence_study
#     - correspondence_summary
#     - correspondence_two_views
#     - hmm_feature_settings
#     - hmm_feature_settings_summary
#     - posture_offsets
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
# # 10 · The correspondence problem: the same action from another posture and another point of view
#
# The papers leave it as future work: the robot learns its actions from its own movements, and must
# recognise them when a person makes them, seen from where the robot stands. The gesture features (the hand
# relative to the torso) change with the person's posture, size, turn and hand. Invariant features
# (`glu.gestures.invariants`) remove these differences frame by frame, online: **centred** (translation:
# the displacement from the first frame), **scaled** (divided by the largest excursion so far),
# **rotated** (the movement's first heading turned straight ahead), **mirrored** (reflected so that the
# hand starts on the right). A recogniser records its features and applies them itself.
#
# We train HMMs on the robot's own grasp, tap and touch (an iCub-like arm in its body frame), and
# separately on one human view (a standing person facing the camera), with each feature set, and recognise
# fresh human gestures one change at a time: the viewpoint (0–180°), a mirror image, a seated posture, body
# size, sensor noise. Then the real data: the two seated taps of effect anticipation, and leave-one-out
# accuracy over seeds and EM settings.

# %% tags=["parameters"]
data: str = None  # data folder, "synthetic", or None: $GLU_DATA_DIR, data/real/, else synthetic
seeds: list[int] = [0, 1, 2, 3, 4]  # study: one training set, EM start and test set per seed
n_train: int = 12  # study: training gestures per action
n_test: int = 10  # study: test gestures per action and condition
feature_sets: list[str] = [
    "raw",
    "centred",
    "centred+scaled",
    "centred+rotated",
    "centred+mirrored",
    "all",
]  # study: feature sets compared
n_states: int = 6  # study: HMM states per action
n_mix: int = 1  # study: Gaussians per state
n_iter: int = 50  # study: most EM iterations
levels: list[str] = None  # study: the test conditions kept, by level ("0°", "mirrored", …); None: all
normalise_body: bool = False  # study: features divided by the 2017 logs' fixed constants; True: by body size
real_features: list[str] = ["raw", "centred", "centred+rotated"]  # real data: feature sets compared
real_settings: list[str] = [
    "glu defaults",
    "reg0.001",
    "M1",
    "mixsplit",
]  # real data: training settings, Q states, M Gaussians, reg covariance prior, or a recipe
real_seeds: list[int] = [0, 1, 2]  # real data: EM seeds, only the first for single Gaussians
real_n_iter: int = 200  # real data: most EM iterations
view_gesture: int = 1  # two-view recording: the seed of the tap it shows (noise-free)
seed: int = 0  # two-view recording: seed of the recognisers' training set and EM
out_dir: str = None  # folder for the outputs; None: the scratch folder build/scratch/<notebook>/

# %%
import matplotlib.pyplot as plt

from glu import plots, recording
from glu.experiments import anticipation, seated
from glu.experiments import correspondence as corr
from glu.gestures.corpus import gesture_sequences, original_test_segments
from glu.gestures.synthetic import View
from glu.hmm import TrainingConfig
from glu.plots import correspondence as cplots
from glu.run import start

out = start("10_correspondence", globals())
conditions = corr.default_conditions(normalise_body)
if levels is not None:
    conditions = [c for c in conditions if c.level in levels]
study = corr.STUDY_TRAINING.replace(n_states=n_states, n_mix=n_mix, n_iter=n_iter)

# %% [markdown]
# ## Recognising human gestures seen otherwise
# Mean accuracy over seeds with its t-interval over seeds (shaded); chance is one in three.

# %%
results = corr.correspondence_study(
    feature_sets=feature_sets,
    conditions=conditions,
    seeds=seeds,
    n_train=n_train,
    n_test=n_test,
    normalise_body=normalise_body,
    config=study,
)
summary = corr.summarise(results)
out.table(results, "correspondence_study")
out.table(summary, "correspondence_summary")
fig, axes = plots.new_figure(2, width=5.2, height=3.6)
for ax, train in zip(axes, corr.TRAIN_SOURCES, strict=True):
    cplots.plot_accuracy_vs_viewpoint(ax, summary, train, legend=ax is axes[-1])
out.figure(fig, "correspondence_viewpoint", source=results.attrs["data_source"])
fig, axes = plots.new_figure(1, width=11, height=3.4)
cplots.plot_accuracy_by_condition(axes[0], summary, "human")
axes[0].set_title("trained on one human view", fontsize=9)
out.figure(fig, "correspondence_conditions", source=results.attrs["data_source"])
corr.main_table(summary, "human")

# %%
corr.main_table(summary, "robot")

# %% [markdown]
# ## Where an invariance costs accuracy
# The paired change of accuracy when one invariance is added (same seeds, same test gestures); bold cells
# have an interval over seeds that excludes zero.

# %%
effects = corr.invariance_effects(results)
out.table(effects, "correspondence_invariance_effects")
fig, axes = plt.subplots(2, 1, figsize=(11, 6.5))
for ax, train in zip(axes, corr.TRAIN_SOURCES, strict=True):
    cplots.plot_invariance_effects(ax, effects, train)
out.figure(fig, "correspondence_invariance_effects", source=results.attrs["data_source"])
costs = effects[effects["costs"]][
    ["train", "features", "baseline", "factor", "level", "delta", "ci_low", "ci_high"]
]
costs

# %% [markdown]
# ## One tap, two viewpoints (Rerun recording)
# The same tap seen from the front and, as a mirror image, from 120° round, through a raw recogniser and an
# invariant one (`all`), both trained on the front human view. The tap is noise-free, so its invariant
# features are exactly the same from both sides (with sensor noise they differ a little, and the study above
# gives the accuracy). `recordings/correspondence_two_views.rrd` shows the person as the camera sees them,
# the raw and aligned features in 3-D, and both posteriors over time.

# %%
raw_rec, inv_rec = (
    corr.train_for(
        "human", f, n_train, seed, normalise_body, TrainingConfig(n_states=n_states, n_mix=n_mix, tol=1e-3)
    )
    for f in ("raw", "all")
)
views = (
    View(yaw_deg=0.0, normalise_body=normalise_body),
    View(yaw_deg=120.0, mirror=True, normalise_body=normalise_body),
)
runs = corr.two_views(raw_rec, inv_rec, "tap", views, seed=view_gesture, noise=0.0)
recording.write_two_views(
    runs,
    out.recording("correspondence_two_views"),
    f"glu-correspondence-two-views-{seed}",
    scene="# One tap, two viewpoints\nRaw features (grey) and invariant features `all` (orange).",
)
curves = corr.two_views_curves(runs)
out.table(curves, "correspondence_two_views")
fig, axes = plots.new_figure(len(runs), width=4.2, height=2.8)
cplots.plot_two_views(axes, curves, "tap")
out.figure(fig, "correspondence_two_views", source=curves.attrs["data_source"])
last = curves[curves["t"] == curves.groupby("view")["t"].transform("max")]
last.pivot_table(index=["view", "recogniser"], columns="action", values="p_hmm").round(3)

# %% [markdown]
# ## The real data: the seated taps
# Where each real segment happens in the torso frame: the seated taps sit apart from every standing
# repetition, so HMMs trained on raw standing features can only judge them by their tails.

# %%
offsets = seated.posture_offsets(out.source)
out.table(offsets, "posture_offsets")
offsets.groupby(["posture", "action"])[["x", "y", "z"]].agg(["min", "max"]).round(2)

# %% [markdown]
# Trained on the standing recordings only (grasp1, tap1, touch1; never on the seated taps), for each feature
# set, training setting and seed: leave-one-segment-out accuracy on the standing segments, and how models
# trained on all of them recognise the two seated taps of effect anticipation (filled points: both as tap).

# %%
if out.source.is_real:
    standing = gesture_sequences(out.source, include_test=False)
    cases = {c.recording for c in anticipation.CASES.values()}
    taps = [s for s in original_test_segments(out.source) if s.recording in cases]
    settings = [seated.parse_setting(s) for s in real_settings]
    grid = seated.feature_settings(
        standing, taps, real_features, settings, real_seeds, TrainingConfig(n_iter=real_n_iter)
    )
    real_summary = seated.feature_settings_summary(grid)
    out.table(grid, "hmm_feature_settings")
    out.table(real_summary, "hmm_feature_settings_summary")
    fig, axes = plots.new_figure(1, width=6, height=3.6)
    cplots.plot_feature_settings(axes[0], grid)
    out.figure(fig, "hmm_feature_settings", source=grid.attrs["data_source"])
    shown = grid.pivot_table(
        index=["features", "setting"], values=["loso_accuracy", "test_correct"], aggfunc=["min", "max"]
    ).round(3)
else:
    shown = "the seated taps are in the real data only"
shown

# %% [markdown]
# **What the study shows** (default parameters). Trained on one human view, HMMs on raw features are near
# chance as soon as the person turns by 30° or more, or moves the other hand; turning the movement's heading
# straight ahead (`rotated`) brings every turn up to 0–180° back close to the front view, reflecting it
# (`mirrored`) brings back mirror images, centring brings back the seated posture and other body sizes, and
# the four together carry a seated, mirrored, turned, bigger person. Each invariance also throws away what it
# normalises, and the map of paired differences shows where that costs accuracy: centring anchors the whole
# gesture on its first frame, so sensor noise on that frame shifts everything (raw features are more robust
# to noise), and turning the heading makes it worse. Trained on the robot's own movements, no feature set
# recognises a person's gestures much above chance, although the robot recognises its own: its hand comes
# down to the table from home above it, a person's comes up from beside the hip, and no shift, scale, turn or
# mirror makes these approaches alike — the correspondence problem is more than a change of viewpoint.
#
# On the real data, the seated taps sit higher and further forward in the torso frame than every standing
# repetition; raw-feature HMMs trained standing never call both of them taps, whatever the recipe, seed or
# setting. Start-centred features do, for every seed, with single Gaussians, a broader covariance prior or
# the originals' mixsplit recipe; glu's default prior lets three Gaussians per state fit one person's path
# too closely and the sphere's tap then goes to the tails again. Centring also raises leave-one-segment-out
# accuracy on the standing segments in every setting. Turning the heading hurts here with glu's recipe: a
# seated tap starts with the sideways strike, which turned straight ahead looks like a reach.
