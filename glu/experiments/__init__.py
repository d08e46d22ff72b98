"""The papers' experiments, each a function returning a tidy DataFrame stamped with its provenance.

* :mod:`~glu.experiments.fusion` — the network and fusion experiments of GLU 2017 and TCDS 2020;
* :mod:`~glu.experiments.gestures` — evaluation of gesture recognition;
* :mod:`~glu.experiments.anticipation` — TCDS effect anticipation, frame by frame;
* :mod:`~glu.experiments.verbal` — the verbal descriptions of TCDS;
* :mod:`~glu.experiments.corpus`, :mod:`~glu.experiments.evaluation`, :mod:`~glu.experiments.intervals`,
  :mod:`~glu.experiments.findings` — every fusion strategy on a simulated corpus, in a factorial design,
  with two-level intervals, and what it finds (``docs/corpus-evaluation.md``);
* :mod:`~glu.experiments.p_hmm` — p_HMM's three readings on held-out real segments;
* :mod:`~glu.experiments.correspondence`, :mod:`~glu.experiments.two_views`, :mod:`~glu.experiments.nested`,
  :mod:`~glu.experiments.seated` — the correspondence problem, synthetic and real
  (``docs/correspondence.md``);
* :mod:`~glu.experiments.replication_text`, :mod:`~glu.experiments.correspondence_text` — the notebooks'
  interpretation, written from their tables;
* :mod:`~glu.experiments.self_supervised`, :mod:`~glu.experiments.online_learning`,
  :mod:`~glu.experiments.learned_recognizers`, :mod:`~glu.experiments.learning_curves` — beyond the self:
  learning people's gestures from what their actions did (notebook 12), with two-level intervals
  (:mod:`~glu.experiments.two_level`);
* :mod:`~glu.experiments.common` — the stamp every table carries (experiment, data source, parameters).

Their figures are drawn by :mod:`glu.plots`.
"""
