"""Speed of training many gesture HMMs: one model at a time against one batched Baum–Welch.

Run on demand (not a test)::

    python benchmarks/bench_training.py [--data DIR] [--repeats N]

Measures, on one BLAS thread, medians over repeats:

1. **leave-one-segment-out on the real standing segments** (glu's recipe and defaults, raw features: 3
   models on every segment + one per held-out segment): each model trained alone by
   :func:`glu.hmm.train` on its list of sequences (a batch of one), against
   :func:`glu.studies.replication.recipes.leave_one_segment_out`, which trains them in one batch
   (:func:`glu.hmm.train` on a mapping of training sets); also the EM alone (the same initial models):
   the readable reference :func:`glu.hmm.em.fit` per model against the one fast EM,
   :func:`glu.hmm._engine.em_batch.fit_many`, in one batch.
   Skipped without the real data;
2. **5-fold cross-validation on synthetic gestures** (20 per action, three actions: 15 models): the same
   two ways (:func:`glu.studies.replication.gestures.cross_validate` is the batched one);
3. **EM against hmmlearn** (20 iterations, the 15 cross-validation models from the same initial models):
   hmmlearn's ``GMMHMM.fit`` per model against glu's fast EM per model (a batch of one each) and in one
   batch. hmmlearn's covariance step takes the scatter about the means before the update, glu's about the
   updated means, so the models differ: the agreement is checked with glu's reference E-step and
   hmmlearn's M-step (``tests/hmm_reference.py``; histories to 1e-8 relative).

Every pair of glu's is checked to give the same models first (histories to 1e-8 relative).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from timing import median_time, report, row

sys.path.insert(
    0, str(Path(__file__).resolve().parents[1] / "tests")
)  # hmmlearn, the reference: tests/hmm_reference.py


def _params(m):
    from glu.hmm.em import GMMHMMParams

    return GMMHMMParams(m.startprob, m.transmat, m.weights, m.means, m.covars)


def _loso_sets(sequences):
    """The training sets of leave-one-segment-out: each action on all segments, then each testable fold."""
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    sets = [(a, [s.xyz for s in sequences if s.action == a]) for a in actions]
    for i, held in enumerate(sequences):
        rest = [s.xyz for j, s in enumerate(sequences) if j != i and s.action == held.action]
        if rest:
            sets.append((held.action, rest))
    return sets


def _cv_sets(sequences, k, seed):
    from glu.studies.replication.gestures import stratified_folds

    folds = stratified_folds([s.action for s in sequences], k, seed)
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    return [
        (a, [s.xyz for s, g in zip(sequences, folds, strict=True) if g != f and s.action == a])
        for f in range(k)
        for a in actions
    ]


def _compare_training(label, sets, batched, repeats, rows):
    """Time training every set alone (``train`` on one list) against ``batched()``; check they agree."""
    from glu.hmm import TrainingConfig, train
    from glu.hmm.initialisation import init_left_to_right

    cfg = TrainingConfig()

    def alone():
        return [train(x, cfg, name=a, warn=False) for a, x in sets]

    ref = alone()
    t_alone = median_time(alone, repeats)
    t_batch = median_time(batched, repeats)
    rows.append(
        row(
            f"{label}: {len(sets)} models, trained in one batch", t_batch, "each model trained alone", t_alone
        )
    )
    # EM alone, from the same initial models
    from glu.hmm import em as bw
    from glu.hmm._engine.em_batch import fit_many

    problems = [
        (x, _params(init_left_to_right(x, cfg.n_states, cfg.n_mix, cfg.covar_reg, 0))) for _, x in sets
    ]
    tols = [cfg.tol * sum(len(s) for s in x) for x, _ in problems]
    fits = [
        bw.fit(x, p, cfg.n_iter, t, cfg.covar_reg) for (x, p), t in zip(problems, tols, strict=True)
    ]  # the reference
    many = fit_many(problems, cfg.n_iter, tols, cfg.covar_reg)
    for a, b, (_, r) in zip(fits, many, ref, strict=True):
        assert len(a.history) == len(b.history) == r.n_iter
        np.testing.assert_allclose(b.history, a.history, rtol=1e-8)
    t_fit = median_time(
        lambda: [
            bw.fit(x, p, cfg.n_iter, t, cfg.covar_reg) for (x, p), t in zip(problems, tols, strict=True)
        ],
        repeats,
    )
    t_many = median_time(lambda: fit_many(problems, cfg.n_iter, tols, cfg.covar_reg), repeats)
    n_iter = [len(a.history) for a in fits]
    rows.append(
        row(
            f"{label}: EM only ({min(n_iter)}–{max(n_iter)} iterations), one batch",
            t_many,
            "the reference EM (glu.hmm.em.fit), each",
            t_fit,
        )
    )


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="data folder with gestures/ (default: $GLU_SHARED_DATA or data/real/)")
    ap.add_argument("--repeats", type=int, default=3, help="repeats of each measurement (default 3)")
    args = ap.parse_args(argv)
    from threadpoolctl import threadpool_limits

    from glu.gestures.corpus import gesture_sequences, synthetic_corpus
    from glu.studies.replication.gestures import cross_validate
    from glu.studies.replication.recipes import leave_one_segment_out

    rows: list[dict] = []
    with threadpool_limits(1):
        source = _real_source(args.data)
        if source is not None:
            standing = gesture_sequences(source, include_test=False)
            _compare_training(
                f"LOSO, {len(standing)} real segments",
                _loso_sets(standing),
                lambda: leave_one_segment_out(standing),
                args.repeats,
                rows,
            )
        else:
            print("no real data found: the leave-one-segment-out rows are skipped")
        corpus = synthetic_corpus(20, seed=0)
        _compare_training(
            "5-fold CV, 60 synthetic gestures",
            _cv_sets(corpus, 5, 0),
            lambda: cross_validate(corpus, 5, 0),
            args.repeats,
            rows,
        )
        hl_rows = _versus_hmmlearn(_cv_sets(corpus, 5, 0), args.repeats)

    report(
        "training",
        "training many gesture HMMs: one batched Baum–Welch against one model at a time (one BLAS thread)",
        rows + hl_rows,
        notes=["every pair is checked to give the same models first (histories to 1e-8 relative)"],
    )
    return 0


def _real_source(data: str | None):
    from glu.data.source import DataSource, resolve_data
    from glu.paths import shared_data_dir

    try:
        source = resolve_data(data)
    except Exception:  # noqa: BLE001 - fall back to the shared copy
        source = None
    if (source is None or not source.is_real) and data is None and shared_data_dir() is not None:
        source = DataSource("real", shared_data_dir(), "GLU_SHARED_DATA")
    return source if source is not None and source.has_gestures else None


def _versus_hmmlearn(sets, repeats):
    """hmmlearn's GMMHMM.fit per model against glu's fast EM per model and in one batch (20 iterations)."""
    from hmm_reference import fit_hmmlearn_update, train_hmmlearn

    from glu.hmm._engine.em_batch import fit_many
    from glu.hmm.initialisation import init_left_to_right

    reg, n_iter = 0.03, 20
    problems = [(x, _params(init_left_to_right(x, 6, 3, reg, 0))) for _, x in sets]

    def hmmlearn():
        return [train_hmmlearn(x, p, n_iter, 1e-300, reg) for x, p in problems]

    for (x, p), h in zip(problems[:3], hmmlearn()[:3], strict=True):  # the E-steps agree
        np.testing.assert_allclose(
            fit_hmmlearn_update(x, p, n_iter, 1e-300, reg).history, h.history, rtol=1e-8
        )
    t_hl = median_time(hmmlearn, repeats)
    t_fit = median_time(lambda: [fit_many([q], n_iter, 1e-300, reg) for q in problems], repeats)
    t_many = median_time(lambda: fit_many(problems, n_iter, 1e-300, reg), repeats)
    what = f"EM, {n_iter} iterations, {len(problems)} CV models"
    return [
        row(f"{what}: glu's EM, each model", t_fit, "hmmlearn GMMHMM.fit, each model", t_hl),
        row(f"{what}: glu's EM, one batch", t_many, "hmmlearn GMMHMM.fit, each model", t_hl),
    ]


if __name__ == "__main__":
    sys.exit(main())
