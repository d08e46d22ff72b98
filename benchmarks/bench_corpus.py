"""Speed of the corpus evaluation: batched HMM scoring, episodes per second, Dask scaling, a million episodes.

Run on demand (not a test)::

    python benchmarks/bench_corpus.py [--data DIR] [--only forward episodes scaling million] [--episodes N]

1. **forward** — many sequences scored against all three models in one vectorised pass
   (:class:`glu.hmm.scoring.BatchScorer`; Q = 6, M = 3, full covariance, 3-D): frame·model evaluations
   per second of CPU time on one core (goal ≥ 5 M), against glu's per-sequence forward and hmmlearn's
   ``score`` per sequence (goal ≥ 50×), with the largest difference to both;
2. **episodes** — one chunk of 2000 episodes end to end on one core: simulation (world, gestures),
   scoring (HMMs, fusion, descriptions, statistics), bootstrap sums; episodes per second;
3. **scaling** — the same sweep on a LocalCluster of 1 and of 2 worker processes (goal: ≥ 1.7× faster);
4. **million** — ``glu evaluate --episodes 1000000`` on a LocalCluster of 2 workers (goal: ≤ 10 minutes).

The models are the default recogniser of a sweep (trained on synthetic gestures, Q = 6, M = 3); the
network is learned from ``--data`` (default: $GLU_DATA_DIR, data/real, else synthetic). The design is one
cell of the factorial sweep (one recogniser seed, uniform actions, the generating network, p_HMM from the
likelihoods): each further reading of an episode (network × p_HMM) adds its fusion and descriptions. Timings
are CPU time of this process where one process does the work (robust to other load on the machine), wall time
for the cluster runs (sensitive to it: the machine's load average is printed with them).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from timing import RESULTS, report, row

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # tests/hmm_reference.py
from hmm_reference import to_hmmlearn  # noqa: E402

ROWS: list[dict] = []
NOTES: list[str] = []


def _load() -> str:
    return " ".join(f"{x:.1f}" for x in os.getloadavg())


def _setup(data: str | None, out: Path):
    from glu.studies.corpus_evaluation.config import config_from_dict
    from glu.studies.corpus_evaluation.sweep import prepare

    one_cell = {"action_prior": ["uniform"], "inference_network": ["generating"], "p_hmm": ["likelihood"]}
    cfg = config_from_dict(
        {
            "chunk_size": 2000,
            "recognizer_seeds": 1,
            "grid": one_cell,
            **({"network": {"data": data}} if data else {}),
        }
    )
    evaluator, provenance = prepare(cfg, out, lambda s: print(f"  {s}"))
    return cfg, evaluator, provenance


def bench_forward(evaluator, repeats: int) -> None:
    from glu.studies.episodes import Condition

    scorer = evaluator.replications[0].scorer
    chunk = evaluator.simulate(Condition(0.02, "front"), 0, 2000)
    X = chunk.features
    n_fm = sum(len(x) for x in X) * scorer.n_models
    times = []
    for _ in range(repeats):
        t = time.process_time()
        curves = scorer.loglik_curves(X)
        times.append(time.process_time() - t)
    batch = statistics.median(times)
    sub = X[:60]
    t = time.process_time()
    ref = [np.stack([m.loglik_curve(x) for m in scorer.models], axis=1) for x in sub]
    per_seq = (time.process_time() - t) / len(sub)
    hl = [to_hmmlearn(m) for m in scorer.models]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = time.process_time()
        scores = np.array([[h.score(x) for h in hl] for x in sub])
        hl_seq = (time.process_time() - t) / len(sub)
    err_glu = max(
        float(np.abs(curves[i, : len(x)] - r).max()) for i, (x, r) in enumerate(zip(sub, ref, strict=True))
    )
    err_hl = float(np.abs(np.array([curves[i, len(x) - 1] for i, x in enumerate(sub)]) - scores).max())
    ours = batch / len(X)
    mean_t = n_fm / scorer.n_models / len(X)
    shape = (
        f"{len(X)} sequences (mean {mean_t:.0f} frames) × {scorer.n_models} models "
        f"(Q={scorer.bank.log_norm.shape[1]}, M={scorer.bank.log_norm.shape[2]}, full covariance)"
    )
    what = f"{n_fm / batch / 1e6:.2f} M frame·model evaluations/s of CPU on one core (goal ≥ 5 M)"
    name = f"forward: {shape}, every prefix, one batch, per sequence"
    ROWS.append(row(name, ours, "glu's per-sequence forward", per_seq, what=what))
    ROWS.append(row(name, ours, "hmmlearn score, whole sequence only", hl_seq, "≥ 50×", hl_seq / ours >= 50))
    NOTES.append(f"forward: max |Δ| to glu's per-sequence curves {err_glu:.1e}, to hmmlearn {err_hl:.1e}")


def bench_episodes(evaluator) -> None:
    from glu.stats import poisson_weights
    from glu.studies.episodes import Condition

    cond, n = Condition(0.02, "front"), 2000
    t0 = time.process_time()
    chunk = evaluator.simulate(cond, 0, n)
    t1 = time.process_time()
    q = evaluator.p_hmm(chunk.features)
    t2 = time.process_time()
    blocks = evaluator.episode_statistics(chunk)[0]  # HMMs again, fusion, descriptions, statistics
    t3 = time.process_time()
    from glu.stats import accumulate

    accumulate(blocks, poisson_weights(n, evaluator.settings.bootstrap, np.random.default_rng(0)))
    t4 = time.process_time()
    total = (t1 - t0) + (t3 - t2) + (t4 - t3)
    what = (
        f"a chunk of {n} on one core ({q.shape[1]} fractions, {len(evaluator.columns)} statistics, "
        f"{evaluator.settings.bootstrap} replicates), CPU time"
    )
    ROWS.append(
        row(f"episodes: one episode end to end ({n / total:.0f} per second per core)", total / n, what=what)
    )
    ROWS.append(
        row("episodes: simulation (world, gestures, features), per episode", (t1 - t0) / n, what=what)
    )
    ROWS.append(
        row("episodes: all statistics (HMMs, fusion, descriptions), per episode", (t3 - t2) / n, what=what)
    )


def _sweep(cfg, workers: int, out: Path):
    from glu.studies.corpus_evaluation.sweep import run_sweep

    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    (out / "recognizers").mkdir()
    shutil.copy(out.parent / "recognizers" / "seed-000.json", out / "recognizers")  # trained once, by _setup
    t, c = time.perf_counter(), time.process_time()
    result = run_sweep(cfg, out, workers=workers, progress=False, log=lambda s: None)
    return time.perf_counter() - t, time.process_time() - c, result.task_cpu_seconds


def bench_scaling(cfg, tmp: Path, episodes: int) -> None:
    c = cfg.with_overrides(episodes=episodes, chunk_size=1000)
    w1, client1, p1 = _sweep(c, 1, tmp / "w1")
    load1 = _load()
    w2, client2, p2 = _sweep(c, 2, tmp / "w2")
    ROWS.append(
        row(
            f"scaling: {c.n_episodes} episodes on a LocalCluster of 2 workers",
            w2,
            "1 worker",
            w1,
            "≥ 1.7×",
            w1 / w2 >= 1.7,
            what=f"wall time; load average {load1} and {_load()} after the runs",
        )
    )
    # On free cores a run takes about its client's CPU (prepare, merge, writes: serial) plus its tasks' CPU
    # divided by the workers; the measured times also hold the waiting for a core on a busy machine.
    NOTES.append(
        f"scaling: CPU of the tasks {p1:.1f} s (1 worker) and {p2:.1f} s (2 workers), client "
        f"{client1:.1f} s and {client2:.1f} s → on 2 free cores "
        f"{(client1 + p1) / (client2 + p2 / 2):.2f}× (tasks as measured), "
        f"{(client1 + p1) / (client1 + p1 / 2):.2f}× (tasks as fast as with 1 worker)"
    )
    same = all(
        (tmp / "w1" / f).read_bytes() == (tmp / "w2" / f).read_bytes()
        for f in ("results.parquet", "differences.parquet")
    )
    NOTES.append(f"scaling: identical tables from 1 and 2 workers: {same}")


def bench_million(cfg, tmp: Path, episodes: int) -> None:
    c = cfg.with_overrides(episodes=episodes, chunk_size=5000)
    wall, _, cpu = _sweep(c, 2, tmp / "million")
    ROWS.append(
        row(
            f"million: glu evaluate --episodes {c.n_episodes}, LocalCluster of 2 workers",
            wall,
            target="≤ 10 min",
            met=wall <= 600,
            what=f"wall time (load average {_load()} after); tasks {1e3 * cpu / c.n_episodes:.2f} ms CPU "
            "per episode",
        )
    )


def main(argv: list[str] | None = None) -> int:
    """Run the chosen benchmarks and print their numbers."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="data folder the network is learned from")
    ap.add_argument(
        "--only",
        nargs="+",
        default=["forward", "episodes", "scaling"],
        choices=["forward", "episodes", "scaling", "million"],
    )
    ap.add_argument(
        "--episodes", type=int, default=48_000, help="episodes of the scaling run (default 48000)"
    )
    ap.add_argument("--million", type=int, default=1_000_000, help="episodes of the million run")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    import hmmlearn.hmm  # noqa: F401 - load every BLAS before limiting threads (a library loaded later is not)
    import scipy.linalg  # noqa: F401
    import scipy.ndimage  # noqa: F401
    from threadpoolctl import threadpool_limits

    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        with threadpool_limits(1):
            cfg, evaluator, prov = _setup(args.data, tmp)
            NOTES.append(f"data: {prov['data_source']}")
            if "forward" in args.only:
                bench_forward(evaluator, args.repeats)
            if "episodes" in args.only:
                bench_episodes(evaluator)
        if "scaling" in args.only:
            bench_scaling(cfg, tmp, args.episodes)
        if "million" in args.only:
            bench_million(cfg, tmp, args.million)
    kept_rows, kept_notes = _kept(args.only)
    report(
        "corpus",
        "the corpus evaluation: batched HMM scoring, episodes per second, Dask scaling, a million episodes",
        kept_rows + ROWS,
        kept_notes + NOTES,
    )
    return 0


def _kept(run: list[str]) -> tuple[list[dict], list[str]]:
    """The rows and notes of the parts not run now (``--only`` updates some), from the last results."""
    import json

    path = RESULTS / "corpus.json"
    if not path.exists():
        return [], []
    old = json.loads(path.read_text(encoding="utf-8"))
    mine = tuple(f"{part}:" for part in run)
    return (
        [r for r in old["rows"] if not r["name"].startswith(mine)],
        [n for n in old["notes"] if not n.startswith(mine) and not n.startswith("data:")],
    )


if __name__ == "__main__":
    sys.exit(main())
