"""The correspondence problem (notebook 10): recognising an action seen from another posture and viewpoint.

* :mod:`~glu.studies.correspondence.experiment` — the synthetic study: recognisers trained on standard
  people facing the camera (or on the robot's own movements), tested on other people, viewpoints and
  postures, with invariant and body-frame features, two-level intervals over seeds and test gestures;
* :mod:`~glu.studies.correspondence.two_views` — one gesture seen from two viewpoints, frame by frame;
* :mod:`~glu.studies.correspondence.seated`, :mod:`~glu.studies.correspondence.nested` — the real data: the
  seated taps, and nested cross-validation on the standing segments;
* :mod:`~glu.studies.correspondence.text` — the interpretation, written from the tables;
* :mod:`~glu.studies.correspondence.figures`, :mod:`~glu.studies.correspondence.recordings`,
  :mod:`~glu.studies.correspondence.readme`.
"""


def parameter_choices() -> dict[str, tuple[str, ...]]:
    """The values of the notebook's study-specific string parameters."""
    from glu.studies.correspondence.experiment import STUDY_FEATURE_NAMES

    return {"feature_sets": STUDY_FEATURE_NAMES}
