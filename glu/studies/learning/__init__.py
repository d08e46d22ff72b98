"""Beyond the self (notebook 12): learning people's gestures from what their actions did to the world.

* :mod:`~glu.studies.learning.self_supervised` — the episodes, and how the robot labels them with its
  affordance network (the labelling schemes and baselines);
* :mod:`~glu.studies.learning.online` — learning online, one episode at a time, from no gesture model;
* :mod:`~glu.studies.learning.study` — every scheme and control over seeds and worlds, on Dask
  (``glu learning-curves``); :mod:`~glu.studies.learning.tables` — the learning curves, the main table
  (equivalence at fixed budgets), the claims; :mod:`~glu.studies.learning.saved` — the saved long runs the
  notebook reads;
* :mod:`~glu.studies.learning.real_person` — the real person, learned from a generator fitted to their
  repetitions, recognised leave-one-segment-out;
* :mod:`~glu.studies.learning.learned_recognizers` — recognisers learned from effects, tested on the real
  gestures (``glu learn-gestures``);
* :mod:`~glu.studies.learning.figures`, :mod:`~glu.studies.learning.recordings`,
  :mod:`~glu.studies.learning.readme`.
"""


def parameter_choices() -> dict[str, tuple[str, ...]]:
    """The values of notebook 12's study-specific string parameters."""
    from glu.studies.learning.self_supervised import AMBIGUITIES, LEARNERS, WORLDS

    return {
        "worlds": tuple(WORLDS),
        "ambiguities": tuple(AMBIGUITIES),
        "curves_ambiguity": tuple(AMBIGUITIES),
        "recorded_scheme": LEARNERS,
    }
