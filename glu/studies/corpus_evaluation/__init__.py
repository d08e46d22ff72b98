"""Every fusion strategy on a simulated corpus (notebook 11, ``glu evaluate``): a factorial design built to
fail.

* :mod:`~glu.studies.corpus_evaluation.corpus` — episodes simulated in chunks (the world:
  :mod:`glu.studies.episodes`), streamed to Parquet;
* :mod:`~glu.studies.corpus_evaluation.evaluation` — what each episode contributes to each metric, for every
  strategy and observed fraction; :mod:`~glu.studies.corpus_evaluation.network_tables` — the network's
  answers, queried once;
* :mod:`~glu.studies.corpus_evaluation.config`, :mod:`~glu.studies.corpus_evaluation.sweep`,
  :mod:`~glu.studies.corpus_evaluation.robots`, :mod:`~glu.studies.corpus_evaluation.tables` — the sweep:
  its settings, running it on Dask resumably, each seed's robot, the merged tables, the saved tables
  notebook 11 reads (:mod:`glu.saved`);
* :mod:`~glu.studies.corpus_evaluation.intervals` — the metrics with their two-level intervals, from sums
  that stream; :mod:`~glu.studies.corpus_evaluation.findings` — what the design finds, cell by cell, with
  verdicts adjusted for multiplicity; :mod:`~glu.studies.corpus_evaluation.conditions` — where the
  conclusions change with the viewpoint, the features and the world;
* :mod:`~glu.studies.corpus_evaluation.p_hmm_readings` — p_HMM's readings on held-out real segments;
* :mod:`~glu.studies.corpus_evaluation.figures`, :mod:`~glu.studies.corpus_evaluation.readme`.
"""


def parameter_choices() -> dict[str, tuple[str, ...]]:
    """The values of the notebook's study-specific string parameters."""
    from glu.gestures.feature_sets import FEATURE_SET_NAMES
    from glu.studies.corpus_evaluation.evaluation import INFERENCE_NETWORKS, P_HMM_READINGS
    from glu.studies.episodes import ACTION_PRIORS, GESTURE_WORLDS, VIEWPOINTS

    return {
        "action_prior": tuple(ACTION_PRIORS),
        "inference_network": tuple(INFERENCE_NETWORKS),
        "p_hmm": tuple(P_HMM_READINGS),
        "effects": tuple(GESTURE_WORLDS),
        "feature_sets": FEATURE_SET_NAMES,
        "viewpoints": tuple(VIEWPOINTS),
    }
