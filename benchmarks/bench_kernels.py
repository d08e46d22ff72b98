"""Speed of the compiled HMM loops (glu.hmm._engine.kernels) against the array code they replaced.

Run on demand (not a test)::

    python benchmarks/bench_kernels.py [--repeats N]

On one BLAS thread, best of N. The array versions below are the ones glu ran before the loops were
compiled (kept here as the reference, as ``bench_fast_paths.py`` keeps its "before" paths); every pair is
checked to agree first. Last, the cost of compiling from an empty cache (what the first run on a fresh
machine pays once) and of loading the cached code, each in a fresh process: the HMM kernels, and the
network's planning loops (:mod:`glu.bn.kernels`, by a first junction-tree query).

1. **scoring** (:func:`glu.hmm.scoring.loglik_many`): synthetic gestures under 3 trained HMMs (Q = 6,
   M = 1 and 3), 30 and 450 sequences;
2. **forward–backward** of batched Baum–Welch (:func:`glu.hmm._engine.kernels.forward_backward_scaled`):
   30, 300 and 2,000 sequences of 120–180 frames, Q = 6;
3. **the mixture log-sum-exp of EM** (:func:`glu.hmm._engine.kernels.mixture_posteriors`): 5 and 40 models'
   frames, Q = 6, M = 3.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from timing import report, row

from glu.hmm.inference import TINY, log_emissions, scaled_step


def best_time(fn, repeats: int) -> float:
    """The fastest of ``repeats`` calls, in seconds."""
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def loglik_many_array(bank, seqs):
    """``loglik_many`` as array code: all emissions at once, then one scaled step per frame for the batch."""
    lengths = np.array([len(X) for X in seqs])
    order = np.argsort(-lengths, kind="stable")
    lengths_sorted = lengths[order]
    S, T = len(seqs), int(lengths_sorted[0])
    alive = np.arange(T)[None, :] < lengths_sorted[:, None]
    log_b = np.zeros((S, T) + bank.log_norm.shape[:-1])
    log_b[alive] = log_emissions(
        np.concatenate([seqs[i] for i in order]), bank.means, bank.chol_inv, bank.log_norm
    )
    n_live = alive.sum(axis=0)
    mx = log_b.max(axis=-1)
    steps = np.zeros(mx.shape)
    alpha = np.zeros(log_b.shape[:1] + log_b.shape[2:])
    with np.errstate(all="ignore"):
        b = np.exp(log_b - mx[..., None])
        for t in range(T):
            n = n_live[t]
            pred = bank.startprob if t == 0 else (alpha[:n, :, None, :] @ bank.transmat)[..., 0, :]
            alpha[:n], steps[:n, t] = scaled_step(pred, b[:n, t], mx[:n, t], log_b[:n, t])
    total = np.cumsum(steps, axis=1)[np.arange(S), lengths_sorted - 1]
    out = np.empty_like(total)
    out[order] = total
    return out


def forward_backward_array(log_b, lengths, startprob, transmat):
    """``kernels.forward_backward_scaled`` as array code: one batched step per frame over live sequences."""
    S, T, Q = log_b.shape
    n_live = (lengths[None, :] > np.arange(T)[:, None]).sum(axis=1)
    alive = np.arange(T)[None, :] < lengths[:, None]
    mx = np.where(alive, log_b.max(axis=2), 0.0)
    with np.errstate(under="ignore", invalid="ignore", over="ignore"):
        b = np.where(alive[..., None], np.exp(log_b - mx[..., None]), 0.0)
    alpha = np.zeros((S, T, Q))
    c = np.ones((S, T))
    with np.errstate(all="ignore"):
        a = startprob * b[:, 0]
        c[:, 0] = a.sum(axis=1)
        alpha[:, 0] = a / c[:, 0, None]
        for t in range(1, T):
            n = n_live[t]
            a = np.matmul(alpha[:n, t - 1, None, :], transmat[:n])[:, 0] * b[:n, t]
            c[:n, t] = s = a.sum(axis=1)
            alpha[:n, t] = a / s[:, None]
        ok = (np.where(alive, c, 1.0) > TINY).all(axis=1)
        loglik = np.where(alive, np.log(c) + mx, 0.0).sum(axis=1)
        beta = np.ones((S, T, Q))
        right = np.zeros((S, T, Q))
        for t in range(T - 2, -1, -1):
            n = n_live[t + 1]
            r = b[:n, t + 1] * beta[:n, t + 1] / c[:n, t + 1, None]
            right[:n, t] = r
            beta[:n, t] = np.matmul(r[:, None, :], np.swapaxes(transmat[:n], 1, 2))[:, 0]
        gamma = np.where(alive[..., None], alpha * beta, 0.0)
        gamma /= np.where(alive, gamma.sum(axis=2), 1.0)[..., None]
        xi = transmat * np.einsum("sti,stj->sij", alpha[:, :-1], right[:, :-1], optimize=True)
    return gamma, xi, loglik, ok


def mixture_array(lc):
    """The mixture log-sum-exp and responsibilities as array code (reductions over the mixture axis)."""
    top = lc.max(axis=3, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    e = np.exp(lc - top)
    mass = e.sum(axis=3)
    return np.log(mass) + top[..., 0], e / mass[..., None]


ROWS: list[dict] = []
_GROUP = [""]


def _row(what: str, before: float, after: float) -> None:
    ROWS.append(row(f"{_GROUP[0]}, {what}", after, "the array code it replaced", before))


_FIRST_CALLS = """
import time, numpy as np
t = time.perf_counter()
from glu.hmm._engine import kernels
from glu.hmm import initialisation as gmm_init
X = np.random.default_rng(0).normal(size=(40, 3))
kernels.forward_backward_scaled(np.zeros((1, 2, 2)), np.array([2]), np.ones((1, 2)) / 2, \
np.ones((1, 2, 2)) / 2)
kernels.loglik_banked([np.zeros((2, 1))], np.zeros((1, 1, 1, 1)), np.ones((1, 1, 1, 1, 1)), \
np.zeros((1, 1, 1)),
                      np.ones((1, 1)), np.ones((1, 1, 1)))
kernels.mixture_posteriors(np.zeros((1, 2, 2, 2)))
gmm_init.fit_gaussian_mixture(X, 3, 0.01, 0)
print(time.perf_counter() - t)
"""


_FIRST_QUERY = """
import time
t = time.perf_counter()
from glu.bn import make_engine
from glu.bn.exchange import from_bif
bif = '''network tiny { }
variable A { type discrete [ 2 ] { a0, a1 }; }
variable B { type discrete [ 2 ] { b0, b1 }; }
variable C { type discrete [ 2 ] { c0, c1 }; }
variable D { type discrete [ 2 ] { d0, d1 }; }
probability ( A ) { table 0.3, 0.7; }
probability ( B | A ) { (a0) 0.9, 0.1; (a1) 0.2, 0.8; }
probability ( C | A ) { (a0) 0.6, 0.4; (a1) 0.5, 0.5; }
probability ( D | B, C ) { (b0, c0) 0.1, 0.9; (b1, c0) 0.7, 0.3; (b0, c1) 0.4, 0.6; (b1, c1) 0.5, 0.5; }
'''
p = make_engine(from_bif(bif), method="junction").query(["A"], evidence={"D": "d1"})["A"]
a0 = 0.3 * (0.9 * (0.6 * 0.9 + 0.4 * 0.6) + 0.1 * (0.6 * 0.3 + 0.4 * 0.5))  # P(A=a0, D=d1) by hand
a1 = 0.7 * (0.2 * (0.5 * 0.9 + 0.5 * 0.6) + 0.8 * (0.5 * 0.3 + 0.5 * 0.5))
assert abs(p[0] - a0 / (a0 + a1)) < 1e-12, p
print(time.perf_counter() - t)
"""


def bench_start() -> None:
    """Compiling from an empty cache, then loading the cached code, each in a fresh process: every HMM kernel
    (:data:`_FIRST_CALLS`), and the network's planning loops (:mod:`glu.bn.kernels`) by a first junction-tree
    query on a four-node network (:data:`_FIRST_QUERY`, checked against the sum by hand)."""
    for what, script in (
        ("first use of every HMM kernel in a fresh process", _FIRST_CALLS),
        ("a first junction-tree query in a fresh process (the network's planning loops)", _FIRST_QUERY),
    ):
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            runs = [
                float(
                    subprocess.run(
                        [sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True
                    ).stdout
                )
                for _ in range(2)
            ]
        ROWS.append(row(f"{what}: compiling from an empty cache", runs[0], what="once per machine"))
        ROWS.append(
            row(f"{what}: loading the cached code, numba's import included", runs[1], what="once per process")
        )


def main(argv: list[str] | None = None) -> int:
    """Run the benchmarks and print before/after times."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    from threadpoolctl import threadpool_limits

    from glu.gestures.corpus import synthetic_corpus
    from glu.hmm import TrainingConfig, train
    from glu.hmm._engine import kernels
    from glu.hmm.inference import left_to_right_transmat
    from glu.hmm.scoring import loglik_many, stack_models

    r = args.repeats
    with threadpool_limits(1):
        corpus = synthetic_corpus(20, seed=1)
        _GROUP[0] = "scoring under 3 HMMs (loglik_many)"
        for M in (1, 3):
            models = [
                train([s.xyz for s in corpus if s.action == a], TrainingConfig(n_mix=M), warn=False).model
                for a in ("grasp", "tap", "touch")
            ]
            bank = stack_models(models)
            for S in (30, 450):
                seqs = [corpus[i % len(corpus)].xyz for i in range(S)]
                np.testing.assert_allclose(loglik_many(bank, seqs), loglik_many_array(bank, seqs), rtol=1e-12)
                _row(
                    f"M = {M}, {S} sequences",
                    best_time(lambda b=bank, q=seqs: loglik_many_array(b, q), r),
                    best_time(lambda b=bank, q=seqs: loglik_many(b, q), r),
                )
        _GROUP[0] = "forward–backward of batched Baum–Welch (Q = 6, 120–180 frames)"
        rng = np.random.default_rng(0)
        for S in (30, 300, 2000):
            T, Q = 180, 6
            lengths = np.sort(rng.integers(120, T + 1, S))[::-1].copy()
            lengths[0] = T
            args_ = (
                rng.normal(-3, 2, (S, T, Q)),
                lengths,
                np.tile(np.eye(Q)[0], (S, 1)),
                np.tile(left_to_right_transmat(Q, 0.9), (S, 1, 1)),
            )
            for a, b in zip(
                kernels.forward_backward_scaled(*args_), forward_backward_array(*args_), strict=True
            ):
                np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)
            _row(
                f"{S} sequences",
                best_time(lambda x=args_: forward_backward_array(*x), r),
                best_time(lambda x=args_: kernels.forward_backward_scaled(*x), r),
            )
        _GROUP[0] = "the mixture log-sum-exp of EM (Q = 6, M = 3)"
        for K, N in ((5, 2000), (40, 2500)):
            lc = rng.normal(0, 5, (K, N, 6, 3))
            for a, b in zip(kernels.mixture_posteriors(lc), mixture_array(lc), strict=True):
                np.testing.assert_allclose(a, b, rtol=1e-12)
            _row(
                f"{K} models x {N} frames",
                best_time(lambda x=lc: mixture_array(x), r),
                best_time(lambda x=lc: kernels.mixture_posteriors(x), r),
            )
    bench_start()
    report(
        "kernels",
        "the compiled HMM loops (glu.hmm._engine.kernels) against the array code they replaced "
        "(one BLAS thread, best of N; every pair checked to agree first), and what compiling glu's loops "
        "costs a fresh machine once",
        ROWS,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
