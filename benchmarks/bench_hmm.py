"""Speed of gesture recognition: glu's forward recursion and streaming step against hmmlearn's ``score``.

Run on demand (not a test)::

    python benchmarks/bench_hmm.py [--data DIR] [--repeats N]

Measures, for a 150-frame sequence:

1. the whole prefix log-likelihood curve ``log L(G_1^t | A)``, t = 1 … 150, of one model: glu computes the
   emissions once and runs one forward pass (target ≤ 2 ms); hmmlearn rescores every prefix with
   ``score`` (about 1.3 s);
2. the log-likelihood of the whole sequence under one model (one ``score`` call);
3. one new frame for all four models of a bank: glu's :class:`~glu.gestures.recognizer.GestureStream` step
   (target ≤ 100 µs) against rescoring the grown prefix with hmmlearn (four ``score`` calls);
4. training one model (Q = 6, M = 3, 20 EM iterations, 20 synthetic gestures): :func:`glu.hmm.train` (its
   initial model, then its compiled Baum–Welch) against hmmlearn's ``GMMHMM.fit`` from the same start;
5. the same streaming step when the recogniser computes invariant features (all four invariances,
   :mod:`glu.gestures.invariants`) from each frame: target at most 20 % more than the raw step.

The models are the originals' four 2013 HMMs (grasp, tap, touch = push, garbage; Q = 6, M = 3) and the
sequence is frames 216–365 of ``tap1_hand`` when the real data is found; otherwise four models trained on
synthetic gestures and a synthetic sequence. Timings are medians over repeats, on one BLAS thread.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import numpy as np
from timing import median_time, report, row

sys.path.insert(
    0, str(Path(__file__).resolve().parents[1] / "tests")
)  # the reference: tests/hmm_reference.py
from hmm_reference import to_hmmlearn, train_hmmlearn  # noqa: E402


def _setup(data: str | None):
    from glu.data.source import DataSource, resolve_data
    from glu.gestures.recognizer import load_original_models
    from glu.gestures.recordings import load_features
    from glu.paths import shared_data_dir

    source = None
    try:
        source = resolve_data(data)
    except Exception:  # noqa: BLE001 - fall back to the shared copy, then synthetic
        source = None
    if (source is None or not source.is_real) and data is None and shared_data_dir() is not None:
        source = DataSource("real", shared_data_dir(), "GLU_SHARED_DATA")
    if source is not None and source.original_hmms() is not None:
        rec = load_original_models(source.original_hmms(), include_garbage=True)
        X = load_features(source.hand_log("tap1_hand"), policy=None).pieces[0].frames(216, 365).xyz
        return rec, X, f"original 2013 models, tap1_hand frames 216–365 ({source.describe()})"
    from glu.gestures.corpus import synthetic_corpus
    from glu.gestures.recognizer import train_recognizer
    from glu.gestures.synthetic import GESTURES
    from glu.hmm import TrainingConfig

    seqs = synthetic_corpus(8, seed=0, actions=GESTURES)
    by_action = {a: [s.xyz for s in seqs if s.action == a] for a in GESTURES}
    rec = train_recognizer(by_action, TrainingConfig(n_iter=20), warn=False)
    X = np.concatenate([s.xyz for s in seqs])[:150]
    return rec, X, "4 models trained on synthetic gestures, a synthetic 150-frame sequence"


def numpy_stream(bank, X: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The plain NumPy streaming step the issue compares with: every frame of X through every model of a
    stacked bank (emissions, one scaled forward step, the posterior over models); the last log-likelihoods.
    No checks and no log-domain fallback (glu's step has both)."""
    alpha, total = None, np.zeros(len(bank.startprob))
    for x in X:
        z = np.einsum("aqmij,aqmj->aqmi", bank.chol_inv, x - bank.means)
        lc = bank.log_norm - 0.5 * (z * z).sum(-1)
        top = lc.max(-1)
        log_b = np.log(np.exp(lc - top[..., None]).sum(-1)) + top
        pred = bank.startprob if alpha is None else np.einsum("aq,aqr->ar", alpha, bank.transmat)
        mx = log_b.max(-1)
        new = pred * np.exp(log_b - mx[:, None])
        c = new.sum(-1)
        alpha, total = new / c[:, None], total + np.log(c) + mx
        p = np.exp(total - total.max())
        p /= p.sum()
    return total


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="data folder with reference-models/ and gestures/")
    ap.add_argument("--repeats", type=int, default=7, help="repeats of each measurement (default 7)")
    args = ap.parse_args(argv)
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        rec, X, what = _setup(args.data)
        T = len(X)
        models = [rec.models[a] for a in rec.actions]
        hl = [to_hmmlearn(m) for m in models]
        m0, h0 = models[0], hl[0]

        # correctness first: the fast paths must agree with hmmlearn
        curve = m0.loglik_curve(X)
        ref = np.array([h0.score(X[:t]) for t in range(1, T + 1)])
        err_curve = float(np.abs(curve - ref).max())
        stream = rec.stream()
        steps = np.array([stream.push(x).loglik for x in X])
        err_stream = float(np.abs(steps[-1] - np.array([h.score(X) for h in hl])).max())

        rows = []
        glu_curve = median_time(lambda: m0.loglik_curve(X), args.repeats, 20)
        hl_curve = median_time(lambda: [h0.score(X[:t]) for t in range(1, T + 1)], max(1, args.repeats // 3))
        rows.append(
            (
                f"prefix log-likelihood curve, {T} frames, 1 model",
                glu_curve,
                hl_curve,
                "≤ 2 ms",
                "score per prefix",
                2e-3,
            )
        )

        glu_full = median_time(lambda: m0.loglik(X), args.repeats, 20)
        hl_full = median_time(lambda: h0.score(X), args.repeats, 5)
        rows.append((f"log L of {T} frames, 1 model", glu_full, hl_full, None, "score", None))

        def push_all() -> None:
            s = rec.stream()
            for x in X:
                s.push(x)

        glu_step = median_time(push_all, args.repeats) / T
        hl_step = median_time(lambda: [h.score(X) for h in hl], args.repeats, 3)
        rows.append(
            (
                f"one new frame, {len(models)} models (streaming)",
                glu_step,
                hl_step,
                "≤ 100 µs",
                "score of the grown prefix",
                100e-6,
            )
        )

        from glu.gestures.corpus import synthetic_corpus
        from glu.hmm import TrainingConfig, train

        sequences = [s.xyz for s in synthetic_corpus(20, seed=1, actions=("tap",))]
        n_train = sum(len(x) for x in sequences)

        from glu.hmm.em import GMMHMMParams
        from glu.hmm.initialisation import init_left_to_right

        config = TrainingConfig(n_iter=20, tol=1e-12)
        init = init_left_to_right(sequences, config.n_states, config.n_mix, config.covar_reg, 0)
        start = GMMHMMParams(init.startprob, init.transmat, init.weights, init.means, init.covars)

        def hmmlearn_em():  # the same start and iterations (train's initialisation included in glu's time)
            return train_hmmlearn(sequences, start, 20, 1e-12 * n_train, config.covar_reg)

        glu_em = median_time(lambda: train(sequences, config, warn=False), max(1, args.repeats // 2))
        hl_em = median_time(hmmlearn_em, max(1, args.repeats // 3))
        rows.append(
            (
                f"EM, 20 iterations, {len(sequences)} sequences ({n_train} frames)",
                glu_em,
                hl_em,
                None,
                "GMMHMM.fit",
                None,
            )
        )

        from glu.gestures.recognizer import Recognizer

        invariant = Recognizer(rec.models, features="all")  # same models: only the features' cost differs

        def push_all_invariant() -> None:
            s = invariant.stream()
            for x in X:
                s.push(x)

        def features_only() -> None:
            s = invariant.features.stream()
            for x in X:
                s.push(x)

        # interleave raw and invariant runs so that load on the machine affects both alike
        raw_t, inv_t, feat_t, plain_t = [], [], [], []
        err_plain = float(np.abs(numpy_stream(rec.bank, X) - steps[-1]).max())
        for _ in range(args.repeats):
            raw_t.append(median_time(push_all, 1) / T)
            plain_t.append(median_time(lambda: numpy_stream(rec.bank, X), 1) / T)
            inv_t.append(median_time(push_all_invariant, 1) / T)
            feat_t.append(median_time(features_only, 1) / T)
        raw_step, inv_step = statistics.median(raw_t), statistics.median(inv_t)
        feat_step = statistics.median(feat_t)
        plain_step = statistics.median(plain_t)

    rows = [
        row(name, g, "hmmlearn " + how, h, target, None if limit is None else g <= limit)
        for name, g, h, target, how, limit in rows
    ]
    rows.append(
        row(
            f"one new frame, {len(models)} models (streaming), against plain NumPy",
            raw_step,
            "a plain NumPy step (numpy_stream)",
            plain_step,
            "at or below the plain step",
            raw_step <= plain_step,
            what=f"GestureStream.push (checks, p_HMM) interleaved with numpy_stream; max |Δ| {err_plain:.1e}",
        )
    )
    rows.append(
        row(
            f"invariant features (all four) of one frame, {invariant.features.name}",
            feat_step,
            what="the invariant features alone, streaming",
        )
    )
    rows.append(
        row(
            f"one new frame, {len(models)} models, with invariant features",
            inv_step,
            "the same step on raw features",
            raw_step,
            "at most 20 % more than raw",
            inv_step <= 1.2 * raw_step,
        )
    )
    models_note = ", ".join(f"{a} (Q={m.n_states}, M={m.n_mix})" for a, m in rec.models.items())
    report(
        "hmm",
        "gesture recognition: glu's forward recursion and streaming step against hmmlearn's score",
        rows,
        notes=[
            f"{what}; models {models_note}; one BLAS thread",
            f"agreement with hmmlearn: prefix curve max |Δ| = {err_curve:.2e}, stream at t={T} max |Δ| = "
            f"{err_stream:.2e}",
        ],
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
