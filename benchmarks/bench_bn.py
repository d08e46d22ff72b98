"""Benchmark glu's BN learning and exact inference against pgmpy, on the same queries.

Run on demand (not part of the tests):  python benchmarks/bench_bn.py [--data DIR] [--json OUT.json]
(default output: ``benchmarks/results/bn.json``, the schema of ``timing.py``).
Targets (2-core machine): one query with affordance evidence ≤ 20 µs; all 49 word marginals ≤ 0.1 ms; a
query with virtual evidence ≤ 50 µs; 10,000 evidence sets ≤ 0.1 s; learning ≤ 0.2 s; `glu query` cold
start ≤ 1 s.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from timing import calls_lasting, fmt, report
from timing import row as result_row

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the reference: tests/bn_reference.py


def timeit(fn, repeat: int = 5, number: int | None = None) -> float:
    """Best-of-``repeat`` seconds per call (``number`` calls per repeat, auto-chosen to last ≥ 0.2 s)."""
    if number is None:
        number = calls_lasting(fn)
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--data", default=None, help="data folder (default: as glu resolves it)")
    ap.add_argument(
        "--json", default=None, help="write the results here (default: benchmarks/results/bn.json)"
    )
    args = ap.parse_args()

    from glu.bn import learn_bn, make_engine
    from glu.data import load_experiments, resolve_data
    from glu.schema import WORDS

    source = resolve_data(args.data)
    df = load_experiments(source, "lab")
    rows = []

    def row(name, ours, theirs, target, reference="pgmpy"):
        rows.append(
            result_row(name, ours, reference if theirs else None, theirs, f"≤ {fmt(target)}", ours <= target)
        )

    t_learn = timeit(lambda: learn_bn(df), repeat=5, number=1)
    bn = learn_bn(df, unseen_words="uniform")  # pgmpy rejects all-zero rows: compare on the uniform model
    eng = make_engine(bn)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        import pgmpy.structure_score as pgmpy_scores
        from bn_reference import to_pgmpy
        from pgmpy.factors.discrete import TabularCPD
        from pgmpy.inference import VariableElimination

        t_pgmpy_import = time.perf_counter() - t0
        ve = VariableElimination(to_pgmpy(bn))

        # learning with pgmpy's BIC as the family score (our K2 loop): the same structure, slower scores
        schema = bn.schema
        bic = pgmpy_scores.BIC(
            df.astype(str), state_names={n: list(schema.values_of(n)) for n in schema.nodes}
        )

        def k2_with_pgmpy_scores():
            for node in list(schema.affordance_nodes[4:]) + list(schema.word_nodes):
                cands = (
                    list(schema.affordance_nodes[: schema.affordance_nodes.index(node)])
                    if node in schema.affordance_nodes
                    else list(schema.affordance_nodes)
                )
                chosen, best = [], bic.local_score(node, ())
                while True:
                    pool = [c for c in cands if c not in chosen]
                    if not pool:
                        break
                    scores = [bic.local_score(node, tuple(chosen + [c])) for c in pool]
                    k = int(np.argmax(scores))
                    if scores[k] <= best:
                        break
                    best = scores[k]
                    chosen.append(pool[k])

        t_learn_pgmpy = timeit(k2_with_pgmpy_scores, repeat=1, number=1)

        ev = {"Action": "tap", "Shape": "sphere", "Size": "small"}
        t_q = timeit(lambda: eng.query(["ObjVel"], ev))
        t_q_pg = timeit(lambda: ve.query(["ObjVel"], evidence=ev, show_progress=False), repeat=3)

        ev_w = {"Size": "big", "Shape": "sphere", "ObjVel": "fast"}
        t_w = timeit(lambda: eng.word_probability_array(ev_w))
        t_w_pg = timeit(
            lambda: [ve.query([w], evidence=ev_w, show_progress=False) for w in WORDS], repeat=1, number=3
        )

        q = np.array([0.1, 0.8, 0.1])
        virt = [TabularCPD("Action", 3, q.reshape(-1, 1), state_names={"Action": ["grasp", "tap", "touch"]})]
        t_v = timeit(lambda: eng.query(["ObjVel"], {"Shape": "sphere", "Size": "small"}, soft={"Action": q}))
        t_v_pg = timeit(
            lambda: ve.query(
                ["ObjVel"],
                evidence={"Shape": "sphere", "Size": "small"},
                virtual_evidence=virt,
                show_progress=False,
            ),
            repeat=3,
        )

        rng = np.random.default_rng(0)
        n = 10_000
        batch = {
            "Action": rng.integers(0, 3, n),
            "Shape": rng.integers(0, 2, n),
            "Size": rng.integers(0, 3, n),
            "HandVel": rng.integers(0, 2, n),
        }
        t_b = timeit(lambda: eng.query_batch(["ObjVel"], batch, errors="nan"), repeat=5, number=1)
        soft_b = rng.dirichlet(np.ones(3), size=n)
        t_bs = timeit(
            lambda: eng.query_batch(["ObjVel", "rolls"], {"Shape": batch["Shape"]}, soft={"Action": soft_b}),
            repeat=5,
            number=1,
        )
        t_b_pg = t_q_pg * n  # extrapolated from the single query

    row("learning: K2 + parameters", t_learn, t_learn_pgmpy, 0.2, "the same K2 with pgmpy's BIC")
    row("query ObjVel | 3 affordance evidence", t_q, t_q_pg, 20e-6, "pgmpy VariableElimination")
    row("all 49 word marginals | 3 evidence", t_w, t_w_pg, 0.1e-3)
    row("query ObjVel | virtual evidence on Action", t_v, t_v_pg, 50e-6)
    row("batch: 10,000 evidence sets (4 nodes)", t_b, t_b_pg, 0.1, "pgmpy, one query × 10,000 (extrapolated)")
    row("batch: 10,000 soft-evidence rows, 2 targets", t_bs, None, 0.1)

    cold = []
    for extra in (["--data", str(source.root) if source.root else "synthetic"],):
        for _ in range(5):
            t0 = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "glu", "query", *extra, "--target", "ObjVel", "--json"],
                check=True,
                capture_output=True,
            )
            cold.append(time.perf_counter() - t0)
    row("`glu query --data` cold start (median of 5)", statistics.median(cold), None, 1.0)
    report(
        "bn",
        "the Affordance–Words network: learning and exact inference, glu against pgmpy on the same queries",
        rows,
        notes=[df.attrs["data_source"], f"pgmpy's import alone: {t_pgmpy_import:.2f} s"],
        out=Path(args.json) if args.json else None,
    )


if __name__ == "__main__":
    main()
