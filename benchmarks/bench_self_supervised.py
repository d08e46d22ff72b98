"""Speed of learning gestures from effects: the notebook's default study, one online update, the CLI.

Run on demand (not a test)::

    python benchmarks/bench_self_supervised.py [--data DIR] [--only notebook update study cli]

1. **notebook** — ``12_learning_from_effects`` at its default size, run headless as
   ``glu reproduce --only 12`` does (into a temporary folder): wall time, and CPU time of the kernel process
   (robust to other load); goal: at most 20 s (what it adds to ``glu reproduce`` on 2 cores, where it runs
   next to the other notebooks);
2. **update** — one online learner (soft labels, the study's HMMs: Q = 6, one Gaussian) updating its models
   after one episode, once it has a model of every action: labels, the E-step of the episode under its
   three models, the stepwise-EM step and the M-step; median, 95th percentile and maximum over 300
   episodes, in CPU time of the update; goal: at most 10 ms;
3. **study** — the study's seeds in this process (``glu.studies.learning.study.learning_study`` at the
   notebook's default size), CPU time, and the lockstep update of all its learners after one episode;
4. **cli** — ``glu learn-gestures --episodes 2000 --labels soft`` (batch weighted EM, Q = 6, M = 3).

Prints a table and writes ``benchmarks/results/self_supervised.json`` in the schema of ``timing.py`` (with
``--only``, the other rows of the file are kept). CPU times are of this process (robust to other load on the
machine); wall times are printed with the machine's load average, since they are not.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from timing import report, row

RESULTS = Path(__file__).resolve().parent / "results" / "self_supervised.json"


def _load() -> str:
    return " ".join(f"{x:.1f}" for x in os.getloadavg())


def _engine(data: str | None):
    from glu.bn import learn_bn, make_engine
    from glu.data import load_experiments, resolve_data

    source = resolve_data(data)
    return make_engine(learn_bn(load_experiments(source))), source


def bench_notebook(data: str | None) -> list[dict]:
    import resource

    from glu.run.reproduce import reproduce

    def children_cpu() -> float:
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        return r.ru_utime + r.ru_stime

    with tempfile.TemporaryDirectory(prefix="glu-bench-12-") as out:
        c0, t0 = children_cpu(), time.perf_counter()
        summary = reproduce(
            data=data, out=out, jobs=1, log=lambda _s: None, progress=False, only=["12"], site=False
        )
        wall, cpu = time.perf_counter() - t0, children_cpu() - c0
    seconds = next(nb["seconds"] for nb in summary["notebooks"] if nb["name"].startswith("12"))
    print(
        f"notebook 12 (default size): {seconds:.1f} s in its kernel (wall), {cpu:.1f} s of CPU in the kernel "
        f"process, {wall:.1f} s with start-up (load {_load()})"
    )
    return [
        {
            "what": "notebook 12_learning_from_effects, default size (wall, s)",
            "seconds": seconds,
            "goal": 20.0,
        },
        {
            "what": "notebook 12_learning_from_effects, default size (CPU of its kernel, s)",
            "seconds": cpu,
            "goal": 20.0,
        },
    ]


def bench_update(data: str | None) -> list[dict]:
    from glu.hmm import TrainingConfig
    from glu.studies.learning import online as ol
    from glu.studies.learning import self_supervised as ss

    engine, _ = _engine(data)
    actions = engine.bn.schema.values_of("Action")
    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 330, seed=0)
    p = ss.network_posteriors(engine, ep.perceived, ep.world)
    rows = []
    for label, config in (
        ("Q=6, M=1 (the study's)", ss.STUDY_TRAINING),
        ("Q=6, M=3 (glu's default)", TrainingConfig()),
    ):
        settings = ol.OnlineSettings(config=config)
        ol.learn_online(
            ep.features[:20], ep.actions[:20], "soft", p[:20], actions, settings
        )  # kernels loaded
        run = ol.learn_online(ep.features, ep.actions, "soft", p, actions, settings)
        t = run.update_seconds[30:]  # every action has its model after the first few episodes
        med, p95, top = np.median(t), np.percentile(t, 95), t.max()
        print(
            f"one online update (soft labels, {label}): median {1e3 * med:.2f} ms, 95 % {1e3 * p95:.2f} ms, "
            f"max {1e3 * top:.2f} ms over {len(t)} episodes (CPU time of the update; load {_load()})"
        )
        rows += [
            {
                "what": f"one online update after one episode, {label}, median (s)",
                "seconds": float(med),
                "goal": 0.010,
            },
            {
                "what": f"one online update after one episode, {label}, 95th percentile (s)",
                "seconds": float(p95),
                "goal": 0.010,
            },
        ]
    return rows


def bench_study(data: str | None) -> list[dict]:
    from glu.studies.learning import study as lc

    engine, _ = _engine(data)
    settings = lc.StudySettings()
    lc.run_seed(engine, 99, lc.StudySettings(episodes=10, seeds=(99,)))  # compiled kernels loaded
    c0, t0 = time.process_time(), time.perf_counter()
    results = lc.learning_study(engine, settings)
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    lockstep = lc.update_times(results)
    n = len(settings.learners())
    print(
        f"study, default size ({len(settings.seeds)} seeds × {settings.episodes} episodes, {n} learners): "
        f"{cpu:.1f} s CPU, {wall:.1f} s wall (load {_load()}); lockstep update of all learners: median "
        f"{1e3 * lockstep['median']:.1f} ms"
    )
    return [
        {"what": "the study's seeds in one process, default size (CPU, s)", "seconds": cpu, "goal": None},
        {
            "what": f"lockstep update of all {n} learners after one episode, median (s)",
            "seconds": lockstep["median"],
            "goal": None,
        },
    ]


def bench_cli(data: str | None) -> list[dict]:
    glu = Path(sys.executable).with_name("glu")
    with tempfile.TemporaryDirectory(prefix="glu-bench-cli-") as tmp:
        cmd = [
            str(glu),
            "learn-gestures",
            "--episodes",
            "2000",
            "--labels",
            "soft",
            "--seed",
            "0",
            "-o",
            f"{tmp}/r.json",
        ] + (["--data", data] if data else [])
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        wall = time.perf_counter() - t0
    print(f"glu learn-gestures --episodes 2000 --labels soft: {wall:.1f} s wall (load {_load()})")
    return [
        {"what": "glu learn-gestures --episodes 2000 --labels soft (wall, s)", "seconds": wall, "goal": None}
    ]


BENCHES = {"notebook": bench_notebook, "update": bench_update, "study": bench_study, "cli": bench_cli}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="data folder (default: as glu finds it)")
    ap.add_argument("--only", nargs="+", choices=list(BENCHES), default=list(BENCHES))
    args = ap.parse_args(argv)
    rows = []
    for name in args.only:
        rows += BENCHES[name](args.data)
    rows = [
        row(
            r["what"],
            r["seconds"],
            target=None if r["goal"] is None else f"≤ {r['goal']:g} s",
            met=None if r["goal"] is None else r["seconds"] <= r["goal"],
        )
        for r in rows
    ]
    kept = []  # rows of the benchmarks not run now stay as they were (``--only`` updates some)
    if RESULTS.exists():
        mine = {r["name"] for r in rows}
        kept = [
            r
            for r in json.loads(RESULTS.read_text(encoding="utf-8")).get("rows", [])
            if r.get("name") not in mine
        ]
    report(
        "self_supervised",
        "learning gestures from effects: the notebook at its default size, one online update, the "
        "study, the CLI",
        kept + rows,
        notes=["CPU times are of the process (robust to other load); wall times are not"],
        out=RESULTS,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
