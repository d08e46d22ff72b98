"""Exact inference in any network: glu against pyAgrum's LazyPropagation, side by side in one process.

Run on demand (not a test)::

    python benchmarks/bench_networks.py [--networks DIR] [--baseline CHECKOUT] [--quick]

1. **All posteriors, one evidence set** on alarm, child and insurance (the bnlearn files in ``DIR``,
   default ``$GLU_SHARED_DATA/bn-networks``): five nodes observed, their values drawn from the network
   (seeded); glu's ``InferenceEngine.query`` of every node against pyAgrum's ``setEvidence`` →
   ``makeInference`` → ``posterior(node).toarray()`` of every node. Target: glu at least as fast.
2. **10,000 evidence sets**: the same five nodes observed in every set, values drawn from the network;
   glu's one ``query_batch`` of every node against pyAgrum's loop over the sets (with ``--quick``, the loop
   is timed on the first 1,000 sets and scaled by 10). glu answers identical sets once; the number of
   distinct sets is reported, and a second row times glu with that turned off (every set propagated).
   Target: glu at least 50 times faster.
3. **GLU's network** (learned from the data glu resolves, unseen words uniform): one query with three
   nodes of evidence, all 49 word marginals, one query with virtual evidence, 10,000 evidence sets —
   this checkout against ``--baseline CHECKOUT`` (another glu checkout, e.g. before this engine), each in
   its own process. Target: within 10 % of the baseline.

Every pair of answers is checked to agree (1e-9) before it is timed. Times are medians of 7 repeats of
enough calls to last ≥ 0.2 s. The table is printed and written as JSON to
``benchmarks/results/networks.json`` in the schema of ``timing.py``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from timing import RESULTS, calls_lasting, machine, median_time, report

NETWORKS = ("alarm", "child", "insurance")
N_OBSERVED, N_BATCH = 5, 10_000


def per_call(fn, repeats: int = 7) -> float:
    """Median over ``repeats`` of the mean seconds per call, ``number`` calls chosen to last ≥ 0.2 s."""
    return median_time(fn, repeats, calls_lasting(fn))


def sample_sets(bn, nodes: list[str], n: int, seed: int) -> dict[str, np.ndarray]:
    """Values of ``nodes`` in ``n`` joint samples of the network (ancestral sampling, seeded): node →
    codes."""
    rng = np.random.default_rng(seed)
    codes: dict[str, np.ndarray] = {}
    todo = list(bn.nodes)
    while todo:
        for node in list(todo):
            if all(p in codes for p in bn.parents[node]):
                cpt = bn.cpts[node]
                rows = (
                    cpt[tuple(codes[p] for p in bn.parents[node])]
                    if bn.parents[node]
                    else np.broadcast_to(cpt, (n, cpt.size))
                )
                cum = np.cumsum(rows, axis=1)
                u = rng.random(n) * cum[:, -1]
                codes[node] = np.minimum((cum <= u[:, None]).sum(axis=1), cpt.shape[-1] - 1)
                todo.remove(node)
    return {v: codes[v] for v in nodes}


def network_rows(name: str, folder: Path, quick: bool, tmp: Path) -> list[dict]:
    import pyagrum as gum

    from glu.bn import make_engine
    from glu.bn.exchange import import_bn, to_xmlbif

    bn = import_bn(folder / f"{name}.bif", renormalise=1e-4 if name == "insurance" else None)
    (tmp / f"{name}.bifxml").write_text(to_xmlbif(bn))  # pyAgrum reads glu's doubles exactly
    g = gum.loadBN(str(tmp / f"{name}.bifxml"))
    ie = gum.LazyPropagation(g)
    eng = make_engine(bn)
    nodes = list(bn.nodes)
    rng = np.random.default_rng(0)
    observed = [nodes[i] for i in sorted(rng.choice(len(nodes), size=N_OBSERVED, replace=False))]
    sets = sample_sets(bn, observed, N_BATCH, seed=1)
    one = {v: int(sets[v][0]) for v in observed}

    def pyagrum_all(ev):
        ie.eraseAllEvidence()
        ie.setEvidence(ev)
        ie.makeInference()
        return {v: ie.posterior(v).toarray() for v in nodes}

    ours, theirs = eng.query(nodes, one), pyagrum_all(one)
    assert max(float(np.abs(ours[v] - theirs[v]).max()) for v in nodes) < 1e-9, name
    t_glu = per_call(lambda: eng.query(nodes, one))
    t_pa = per_call(lambda: pyagrum_all(one))
    rows = [
        {
            "name": f"{name}: all posteriors, one evidence set",
            "what": f"{len(nodes)} nodes, {N_OBSERVED} observed ({', '.join(observed)}); glu "
            f"{type(eng).__name__}",
            "glu_s": t_glu,
            "reference": f"pyAgrum {gum.__version__} LazyPropagation",
            "reference_s": t_pa,
            "ratio": t_pa / t_glu,
            "target": "ratio >= 1",
            "met": t_pa >= t_glu,
        }
    ]
    batch = eng.query_batch(nodes, sets)  # the first call plans for the pattern; time the next ones
    for i in (0, N_BATCH // 2, N_BATCH - 1):
        ref = pyagrum_all({v: int(sets[v][i]) for v in observed})
        assert max(float(np.abs(batch[v][i] - ref[v]).max()) for v in nodes) < 1e-9, (name, i)
    t_glu_b = per_call(lambda: eng.query_batch(nodes, sets), repeats=5)
    loop = 1000 if quick else N_BATCH
    evs = [{v: int(sets[v][i]) for v in observed} for i in range(loop)]
    t0 = time.perf_counter()
    for ev in evs:
        pyagrum_all(ev)
    t_pa_b = (time.perf_counter() - t0) * N_BATCH / loop
    distinct = len(np.unique(np.stack([sets[v] for v in observed], axis=1), axis=0))
    eng.deduplicate = False
    t_glu_every = per_call(lambda: eng.query_batch(nodes, sets), repeats=3)
    eng.deduplicate = True
    rows.append(
        {
            "name": f"{name}: {N_BATCH:,} evidence sets, all posteriors",
            "what": f"{N_OBSERVED} nodes observed in every set, values sampled from the network "
            f"({distinct:,} distinct sets); pyAgrum's loop"
            + (f" timed on {loop:,} sets, scaled to {N_BATCH:,}" if loop < N_BATCH else ""),
            "glu_s": t_glu_b,
            "reference": f"pyAgrum {gum.__version__} LazyPropagation, one set at a time",
            "reference_s": t_pa_b,
            "ratio": t_pa_b / t_glu_b,
            "target": "ratio >= 50",
            "met": t_pa_b / t_glu_b >= 50,
        }
    )
    rows.append(
        {
            "name": f"{name}: {N_BATCH:,} evidence sets, every set propagated",
            "what": "as above, with glu's answer-once for identical sets turned off (deduplicate=False): "
            "the propagation itself",
            "glu_s": t_glu_every,
            "reference": rows[-1]["reference"],
            "reference_s": t_pa_b,
            "ratio": t_pa_b / t_glu_every,
            "target": "ratio >= 50",
            "met": t_pa_b / t_glu_every >= 50,
        }
    )
    return rows


GLU_SCRIPT = """
import json, statistics, sys, time
import numpy as np
sys.path.insert(0, sys.argv[1])
from glu.bn import learn_bn, make_engine
from glu.data import load_experiments, resolve_data
sys.path.insert(0, sys.argv[2])
from bench_networks import per_call
df = load_experiments(resolve_data(sys.argv[3] if len(sys.argv) > 3 else None), "lab")
eng = make_engine(learn_bn(df, unseen_words="uniform"))
words = getattr(eng, "word_probability_array", None) or eng.word_probabilities
ev = {"Action": "tap", "Shape": "sphere", "Size": "small"}
ev_w = {"Size": "big", "Shape": "sphere", "ObjVel": "fast"}
q = np.array([0.1, 0.8, 0.1])
rng = np.random.default_rng(0)
n = 10_000
batch = {"Action": rng.integers(0, 3, n), "Shape": rng.integers(0, 2, n), "Size": rng.integers(0, 3, n),
         "HandVel": rng.integers(0, 2, n)}
out = {
    "single": per_call(lambda: eng.query(["ObjVel"], ev)),
    "words": per_call(lambda: words(ev_w)),
    "virtual": per_call(lambda: eng.query(["ObjVel"], {"Shape": "sphere", "Size": "small"}, \
soft={"Action": q})),
    "batch": per_call(lambda: eng.query_batch(["ObjVel"], batch, errors="nan"), repeats=5),
    "answers": [eng.query(["ObjVel"], ev)["ObjVel"].tolist(), list(map(float, words(ev_w)))],
}
print(json.dumps(out))
"""

GLU_WHAT = {
    "single": "one query: ObjVel | Action, Shape, Size",
    "words": "all 49 word marginals | Size, Shape, ObjVel",
    "virtual": "one query: ObjVel | Shape, Size, virtual evidence on Action",
    "batch": "10,000 evidence sets (4 nodes observed), one target",
}


def glu_rows(baseline: Path | None, data: str | None, tmp: Path) -> list[dict]:
    script = tmp / "glu_network.py"
    script.write_text(GLU_SCRIPT)
    here = Path(__file__).resolve().parent

    def run(checkout: Path) -> dict:
        args = [sys.executable, str(script), str(checkout), str(here)] + ([data] if data else [])
        r = subprocess.run(args, capture_output=True, text=True, check=True)
        return json.loads(r.stdout)

    ours = run(here.parent)
    theirs = run(baseline) if baseline else None
    if theirs:
        for a, b in zip(ours["answers"], theirs["answers"], strict=True):
            assert np.allclose(a, b, atol=1e-12), "the baseline answers differently"
    rows = []
    for key, what in GLU_WHAT.items():
        ref = theirs[key] if theirs else None
        rows.append(
            {
                "name": f"GLU's network: {what}",
                "what": "this checkout"
                + (" against the baseline checkout, each in its own process" if ref else ""),
                "glu_s": ours[key],
                "reference": "glu before the junction tree engine (--baseline)" if ref else None,
                "reference_s": ref,
                "ratio": ref / ours[key] if ref else None,
                "target": "ratio >= 1/1.1 (no more than 10 % slower)",
                "met": (ours[key] <= 1.1 * ref) if ref else None,
            }
        )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument(
        "--networks", type=Path, help="folder of the bnlearn files (default: $GLU_SHARED_DATA/bn-networks)"
    )
    ap.add_argument("--baseline", type=Path, help="another glu checkout to compare GLU's network with")
    ap.add_argument("--data", help="data for GLU's network (default: as glu resolves it)")
    ap.add_argument("--quick", action="store_true", help="time pyAgrum's loop on 1,000 sets and scale by 10")
    ap.add_argument("--out", type=Path, default=RESULTS / "networks.json", help="JSON file to write")
    args = ap.parse_args()

    from glu.paths import shared_data_dir

    folder = args.networks
    if folder is None:
        shared = shared_data_dir()
        folder = shared / "bn-networks" if shared else None
    note = machine()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        if folder is not None and folder.is_dir():
            for name in NETWORKS:
                rows += network_rows(name, folder, args.quick, Path(tmp))
        else:
            print("# no bnlearn networks found (give --networks DIR): only GLU's network")
        rows += glu_rows(args.baseline, args.data, Path(tmp))
    report(
        "networks",
        "exact inference in any network: glu against pyAgrum's LazyPropagation (bnlearn networks), "
        "and GLU's own network against a baseline checkout",
        rows,
        out=args.out,
        machine_note=note,
    )


if __name__ == "__main__":
    main()
