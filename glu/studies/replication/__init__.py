"""The replication of GLU 2017 and TCDS 2020 (notebooks 01–07 and 09), checked against the authors' files.

* :mod:`~glu.studies.replication.gestures` — gesture recognition evaluated: cross-validation on synthetic
  gestures, the real recordings, the original 2013 models; :mod:`~glu.studies.replication.recipes` — glu's
  training recipe against the originals' mixsplit on the same segments;
* :mod:`~glu.studies.replication.fusion` — the network and fusion experiments;
* :mod:`~glu.studies.replication.verbal` — the verbal descriptions of TCDS;
* :mod:`~glu.studies.replication.text` — the notebooks' interpretation, written from their tables;
* figures: :mod:`~glu.studies.replication.gesture_figures`, :mod:`~glu.studies.replication.network_figures`,
  :mod:`~glu.studies.replication.fusion_figures`, :mod:`~glu.studies.replication.verbal_figures`;
* :mod:`~glu.studies.replication.readme` — the README's bullets.
"""
