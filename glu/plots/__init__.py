"""One plotting function per figure, one signature: ``plot_x(ax, frame, …) -> Axes``.

Each function draws a tidy frame of :mod:`glu.experiments` (or a model) on the axes it is given, first
argument (a sequence of axes for a multi-panel figure), and returns them. The look shared by every figure
(colours, sizes, the data-source footer, deterministic PNG and SVG) is in :mod:`glu.plots.style`. The
functions live in one module per part of the story — :mod:`~glu.plots.gestures`,
:mod:`~glu.plots.network`, :mod:`~glu.plots.fusion`, :mod:`~glu.plots.anticipation`,
:mod:`~glu.plots.verbal`, :mod:`~glu.plots.evaluation`, :mod:`~glu.plots.corpus`,
:mod:`~glu.plots.learning` — and are all importable
from here. A few build a whole figure (``*_figure``) where its layout is part of what it says.
:mod:`~glu.plots.overlap` checks that no text of a figure covers another or the data.
"""

from glu.plots.anticipation import anticipation_figure, plot_anticipation, shared_ylim
from glu.plots.corpus import (
    calibration_figure,
    differences_figure,
    early_recognition_figure,
    p_hmm_calibration_figure,
    strategies_vs_noise_figure,
)
from glu.plots.evaluation import (
    plot_by_viewpoint,
    plot_differences,
    plot_early_recognition,
    plot_metric_vs_noise,
    plot_reliability,
)
from glu.plots.fusion import plot_fusion_on_gestures, plot_soft_sweep, plot_tap_thresholds
from glu.plots.gestures import (
    plot_accuracy_vs_noise,
    plot_confusion,
    plot_segment_scores,
    plot_segmentation,
    plot_segmentations,
)
from glu.plots.learning import (
    episodes_to_match_figure,
    learning_curves_figure,
    plot_episodes_to_match,
    plot_learning_curves,
    plot_real_gestures,
    real_gestures_figure,
)
from glu.plots.network import (
    plot_action_vs_soft_evidence,
    plot_effect_prediction,
    plot_effect_vs_soft_evidence,
    plot_structure,
    plot_unseen_rows,
    plot_word_change,
)
from glu.plots.style import ACTION_COLORS, VALUE_COLORS, new_figure, save_figure, stamp
from glu.plots.verbal import and_but_figure, plot_and_but, plot_nbest, plot_sampling

__all__ = [
    "ACTION_COLORS",
    "and_but_figure",
    "anticipation_figure",
    "calibration_figure",
    "differences_figure",
    "p_hmm_calibration_figure",
    "early_recognition_figure",
    "strategies_vs_noise_figure",
    "shared_ylim",
    "VALUE_COLORS",
    "new_figure",
    "plot_accuracy_vs_noise",
    "plot_by_viewpoint",
    "plot_differences",
    "plot_early_recognition",
    "plot_metric_vs_noise",
    "plot_reliability",
    "plot_action_vs_soft_evidence",
    "plot_and_but",
    "plot_anticipation",
    "plot_confusion",
    "plot_effect_prediction",
    "plot_effect_vs_soft_evidence",
    "plot_episodes_to_match",
    "plot_fusion_on_gestures",
    "plot_learning_curves",
    "learning_curves_figure",
    "episodes_to_match_figure",
    "real_gestures_figure",
    "plot_nbest",
    "plot_real_gestures",
    "plot_sampling",
    "plot_segment_scores",
    "plot_segmentation",
    "plot_segmentations",
    "plot_soft_sweep",
    "plot_structure",
    "plot_tap_thresholds",
    "plot_unseen_rows",
    "plot_word_change",
    "save_figure",
    "stamp",
]
