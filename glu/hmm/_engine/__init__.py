"""The fast paths of :mod:`glu.hmm` (private): what the package's functions call when speed matters.

* :mod:`~glu.hmm._engine.em_batch` — the one fast EM: weighted Baum–Welch for a batch of models (one model
  is a batch of one), and its E-step (:func:`~glu.hmm._engine.em_batch.estep`), which online learning and
  every trainer run;
* :mod:`~glu.hmm._engine.kernels` — compiled loops (numba): the scaled forward–backward of the E-step, the
  banked forward recursion of scoring (:func:`glu.hmm.scoring.loglik_many`), the mixtures' log-sum-exp
  (each compiled by :func:`glu.jit.compiled`);
* :mod:`~glu.hmm._engine.gmm` — the compiled loops of the initial mixtures (k-means, mixture EM).

Each is tested against the readable reference (:mod:`glu.hmm.inference`, :mod:`glu.hmm.em`, scikit-learn);
edit the reference first, then the fast path, and keep the tests equal. Only :mod:`glu.hmm`'s own modules
import from here; everything else uses their public names.
"""
