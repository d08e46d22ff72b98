"""The fast paths of :mod:`glu.hmm` (private): what the package's functions call when speed matters.

* :mod:`~glu.hmm._engine.kernels` — compiled loops (numba): the scaled forward–backward of batched EM, the
  banked forward recursion, the mixtures' log-sum-exp; :func:`~glu.hmm._engine.kernels.compiled` for others;
* :mod:`~glu.hmm._engine.batch` — many sequences scored against a bank of models in one pass;
* :mod:`~glu.hmm._engine.em_batch` — Baum–Welch for many independent models at once;
* :mod:`~glu.hmm._engine.gmm` — the compiled loops of the initial mixtures (k-means, mixture EM);
* :mod:`~glu.hmm._engine.online` — the E-step of one sequence under many models (online learning).

Each is tested against the readable reference (:mod:`glu.hmm.inference`, :mod:`glu.hmm.em`, scikit-learn);
edit the reference first, then the fast path, and keep the tests equal.
"""
