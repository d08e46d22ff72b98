"""Beyond the self (notebook 12): learning people's gestures from what their actions did to the world.

* :mod:`~glu.studies.learning.self_supervised` — the episodes, and how the robot labels them with its
  affordance network (the labelling schemes and baselines);
* :mod:`~glu.studies.learning.online` — learning online, one episode at a time, from no gesture model;
* :mod:`~glu.studies.learning.study` — learning curves of every scheme with two-level intervals, on Dask
  (``glu learning-curves``);
* :mod:`~glu.studies.learning.learned_recognizers` — recognisers learned from effects, tested on the real
  gestures (``glu learn-gestures``);
* :mod:`~glu.studies.learning.figures`, :mod:`~glu.studies.learning.recordings`,
  :mod:`~glu.studies.learning.readme`.
"""
