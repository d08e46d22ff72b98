"""Effect anticipation (TCDS 2020 Fig. 5, notebook 08): what a tap will do to the object while the hand moves.

* :mod:`~glu.studies.anticipation.experiment` — the gesture HMMs score every prefix of the hand trajectory,
  and every few frames their posterior enters the network as soft evidence (:class:`AnticipationRun`);
* :mod:`~glu.studies.anticipation.figures` — the figure; :mod:`~glu.studies.anticipation.recordings` — the
  Rerun recording;
* :mod:`~glu.studies.anticipation.readme` — the README's bullet.

Shared: the correspondence study (notebook 10) and learning from effects (notebook 12) reuse the experiment.
"""
