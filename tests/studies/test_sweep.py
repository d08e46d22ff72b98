"""glu evaluate: settings and their errors, resuming, and the same table locally and on a real Dask
cluster."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_run import run

from glu.errors import DataError, ModelError
from glu.studies.corpus_evaluation.config import config_from_dict, config_from_parameters, load_config
from glu.studies.corpus_evaluation.sweep import run_sweep

SMALL = """\
episodes = 64
chunk_size = 4
seed = 3
recognizer_seeds = 2

[grid]
noise = [0.0, 0.05]
viewpoints = ["front", "seated"]
fractions = [0.5, 1.0]
action_prior = ["network"]
inference_network = ["generating", "learned"]
learn_experiments = [150]
p_hmm = ["likelihood", "calibrated"]
effects = ["action"]
features = ["raw"]

[recognizer]
n_per_action = 6
n_states = 3
n_mix = 1
n_iter = 10
calibration_per_action = 4

[network]
data = "synthetic"

[evaluation]
bootstrap = 20
"""
TABLES = (
    "results.parquet",
    "differences.parquet",
    "reliability.parquet",
    "seeds.parquet",
    "calibration.parquet",
    "summary.json",
)


def quiet(_msg: str) -> None:
    pass


@pytest.fixture(scope="module")
def config_file(tmp_path_factory):
    p = tmp_path_factory.mktemp("cfg") / "small.toml"
    p.write_text(SMALL)
    return p


@pytest.fixture(scope="module")
def synchronous(config_file, tmp_path_factory):
    """The reference run: every chunk in this process."""
    out = tmp_path_factory.mktemp("sync")
    result = run_sweep(load_config(config_file), out, scheduler="synchronous", log=quiet)
    return out, result


def same_tables(a: Path, b: Path) -> None:
    for name in TABLES:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def test_the_tables(synchronous):
    out, result = synchronous
    assert result.computed == 8 and result.reused == 0  # 4 conditions × 2 chunks of 4 episodes per seed
    table = pd.read_parquet(out / "results.parquet")
    assert set(table.columns) >= {
        "action_prior",
        "inference_network",
        "learn_experiments",
        "p_hmm",
        "noise",
        "viewpoint",
        "target",
        "strategy",
        "fraction",
        "metric",
        "estimate",
        "ci_low",
        "ci_high",
    }
    assert set(table.viewpoint) == {"front", "seated", "all"}
    assert set(table.p_hmm) == {"likelihood", "calibrated"} and set(table.action_prior) == {"network"}
    assert set(zip(table.inference_network, table.learn_experiments, strict=True)) == {
        ("generating", 0),
        ("learned", 150),
    }
    assert {"network", "true_action"} <= set(table[table.target == "effect"].strategy)
    full = table[(table.viewpoint == "all") & table.noise.isna()]
    assert (full.n_episodes == 64).all()  # 4 conditions × 2 seeds × 8 episodes
    assert (full.ci_low <= full.estimate + 1e-12).all() and (full.estimate <= full.ci_high + 1e-12).all()
    assert set(full.metric) == {"accuracy", "log_loss", "brier", "ece"}
    assert set(full[full.target == "words"].metric) == {"log_loss", "brier"}
    ece = full[full.metric == "ece"]
    assert ece.ece_plugin.notna().all() and full[full.metric != "ece"].ece_plugin.isna().all()
    assert result.metrics.attrs["experiment"] == "corpus_evaluation"
    assert "synthetic data" in result.summary["data_source"] and "/" not in result.summary["data_source"]
    diffs = pd.read_parquet(out / "differences.parquet")
    assert set(diffs.verdict) <= {"better", "worse", "no difference"}
    assert set(diffs.verdict_adjusted) <= {"better", "worse", "no difference"}
    assert (diffs.p_adjusted >= diffs.p_value - 1e-12).all() and diffs.p_value.between(0, 1).all()
    # three families: per viewpoint, per noise level, pooled over both
    assert set(zip(diffs.viewpoint, diffs.noise.fillna(-1), strict=True)) == {
        ("front", -1), ("seated", -1), ("all", 0.0), ("all", 0.05), ("all", -1)
    }  # fmt: skip
    seeds = pd.read_parquet(out / "seeds.parquet")
    assert set(seeds.recognizer_seed) == {0, 1} and seeds.estimate.notna().any()
    cal = pd.read_parquet(out / "calibration.parquet")
    assert len(cal) == 4 and cal.beta.between(0, 1).all()  # 2 seeds × 2 fractions
    assert set(cal.reading) == {"calibrated"} and cal.at_bound.dtype == bool
    rel = pd.read_parquet(out / "reliability.parquet")
    assert {"gesture"} <= set(rel[rel.target == "action"].strategy)  # p_HMM's own reliability
    assert (out / "recognizers" / "seed-001-raw.json").is_file()


def test_the_seeds_make_the_pooled_estimate(synchronous):
    """Each seed's estimates pool (with equal episodes per seed) to the table's estimate; the seeds differ."""
    out, _ = synchronous
    table = pd.read_parquet(out / "results.parquet")
    seeds = pd.read_parquet(out / "seeds.parquet")
    keys = ["inference_network", "learn_experiments", "p_hmm", "target", "strategy", "fraction", "metric"]
    keys.append("features")
    pooled = table[(table.viewpoint == "all") & table.noise.isna() & (table.metric == "accuracy")]
    mean = seeds[seeds.metric == "accuracy"].groupby(keys).estimate.mean()
    merged = pooled.set_index(keys).estimate
    pd.testing.assert_series_equal(
        mean.sort_index(), merged.loc[mean.index].sort_index(), check_names=False, rtol=1e-12
    )
    g = seeds[(seeds.strategy == "gesture") & (seeds.metric == "accuracy")]
    assert g.groupby("recognizer_seed").estimate.mean().nunique() == 2


def test_resume_computes_only_the_missing_chunks(config_file, synchronous, tmp_path):
    ref, _ = synchronous
    out = tmp_path / "resume"
    shutil.copytree(ref, out)
    (out / "chunks" / "c002-000001.npz").unlink()  # as if interrupted before this chunk
    (out / "chunks" / ".c003-000000.npz.abcd.npz").write_bytes(b"half a file")  # an interrupted write
    for name in TABLES:
        (out / name).unlink()
    result = run_sweep(load_config(config_file), out, scheduler="synchronous", log=quiet)
    assert (result.computed, result.reused) == (1, 7)
    assert not list((out / "chunks").glob(".*"))  # the half-written file is gone
    same_tables(ref, out)


def test_a_sweep_in_pieces_gives_the_same_tables(config_file, synchronous, tmp_path):
    ref, _ = synchronous
    config = load_config(config_file)
    first = run_sweep(config, tmp_path, scheduler="synchronous", max_chunks=3, log=quiet)
    assert first.computed == 3 and first.metrics.empty and not (tmp_path / "results.parquet").exists()
    rest = run_sweep(config, tmp_path, scheduler="synchronous", log=quiet)
    assert (rest.computed, rest.reused) == (5, 3)
    same_tables(ref, tmp_path)


def test_a_folder_with_other_settings_is_refused(config_file, synchronous):
    ref, _ = synchronous
    other = load_config(config_file).with_overrides(seed=4)
    with pytest.raises(DataError, match="holds a sweep with other settings"):
        run_sweep(other, ref, scheduler="synchronous", log=quiet)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for_port(port: int, proc: subprocess.Popen, timeout: float = 60) -> None:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if proc.poll() is not None:
            raise RuntimeError(f"the dask process exited with {proc.returncode}")
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.2)
    raise TimeoutError(f"nothing listens on 127.0.0.1:{port}")


@pytest.fixture
def dask_cluster(tmp_path):
    """A real `dask scheduler` and `dask worker` on 127.0.0.1 (free ports), stopped afterwards."""
    port = _free_port()
    env = {**os.environ, "DASK_DISTRIBUTED__LOGGING__DISTRIBUTED": "error"}
    cli = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    sched = subprocess.Popen(
        [
            *cli,
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--no-dashboard",
            "--dashboard-address",
            "127.0.0.1:0",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
        cwd=tmp_path,
    )
    procs = [sched]
    try:
        _wait_for_port(port, sched)
        worker = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "distributed.cli.dask_worker",
                f"tcp://127.0.0.1:{port}",
                "--nworkers",
                "1",
                "--nthreads",
                "1",
                "--no-dashboard",
                "--host",
                "127.0.0.1",
                "--local-directory",
                str(tmp_path / "w"),
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            env=env,
            cwd=tmp_path,
        )
        procs.append(worker)
        yield f"tcp://127.0.0.1:{port}"
    finally:  # the worker first: a nanny whose scheduler is already gone waits out its timeouts (8 s)
        for p in reversed(procs):
            p.terminate()
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def test_a_real_scheduler_and_worker_give_the_local_runs_table(
    config_file, synchronous, dask_cluster, tmp_path, capsys
):
    """The acceptance test of the issue: `--scheduler tcp://127.0.0.1:PORT` equals the LocalCluster run."""
    ref, _ = synchronous
    local, remote = tmp_path / "local", tmp_path / "remote"
    status, out, err = run(
        capsys, "evaluate", "--config", str(config_file), "--workers", "1", "-o", str(local)
    )
    assert status == 0, err
    assert "8 chunks computed" in out and "accuracy" in out
    status, out, err = run(
        capsys, "evaluate", "--config", str(config_file), "--scheduler", dask_cluster, "-o", str(remote)
    )
    assert status == 0, err
    assert f"on {dask_cluster}" in err
    same_tables(local, remote)
    same_tables(ref, local)


def test_an_unreachable_scheduler_is_one_line(config_file, tmp_path, capsys):
    status, out, err = run(
        capsys,
        "evaluate",
        "--config",
        str(config_file),
        "--scheduler",
        f"tcp://127.0.0.1:{_free_port()}",
        "-o",
        str(tmp_path / "x"),
    )
    assert status == 2 and err.count("\n") == 1 and "cannot reach the Dask scheduler" in err, err


@pytest.mark.parametrize(
    ("toml", "message"),
    [
        ("episodes = 0\n", "episodes=0: a whole number from 1"),
        ("episode = 10\n", "unknown key 'episode' in the top level; allowed: episodes"),
        ("[grid]\nnoise = [-1.0]\n", "grid.noise"),
        ("[grid]\nviewpoints = ['upside']\n", "unknown viewpoint 'upside'"),
        ("[grid]\nstrategies = ['best']\n", "unknown strategy 'best'"),
        ("[grid]\nfractions = [0.0]\n", "fractions"),
        ("[views.left]\nyaw = 3\n", "unknown key 'yaw' in views.left; allowed: yaw_deg"),
        ("[scenario.Action]\nkick = 1\n", "no value 'kick'"),
        ("[scenario.Action]\ntap = 1\n", "applies only with grid.action_prior"),
        ("[grid]\np_hmm = ['raw']\n", "grid.p_hmm: unknown value 'raw'; allowed: likelihood, per-frame"),
        ("[grid]\nfeatures = ['bodily']\n", "grid.features: unknown value 'bodily'; allowed: raw, centred"),
        ("[grid]\neffects = ['magic']\n", "grid.effects: unknown value 'magic'; allowed: action, gesture"),
        ("[views.left]\ntracker = 'kinect'\n", "views.left.tracker='kinect'; allowed: ideal, occluding"),
        ("[grid]\naction_prior = ['empirical']\n", "grid.action_prior: unknown value 'empirical'"),
        ("[grid]\ninference_network = ['oracle']\n", "allowed: generating, learned"),
        ("[grid]\nlearn_experiments = [5]\n", "grid.learn_experiments=5: a whole number from 10"),
        ("recognizer_seeds = 0\n", "recognizer_seeds=0: a whole number from 1"),
        ("[recognizer]\nfile = 'r.json'\n", "needs recognizer_seeds = 1"),
        ("[network]\nwords = 'asl'\n", "network.words='asl'; allowed: lab, asr"),
        ("[evaluation]\neffect_evidence = ['ObjVel']\n", "leave it out"),
        ("[recognizer]\nn_states = 0\n", "recognizer.n_states=0"),
        ("episodes = [\n", "small.toml"),
        ("[grid]\nnoise = [0.0, 0.0]\n", "grid.noise: each value may appear once"),
        ("[grid]\nlearn_experiments = []\n", "grid.learn_experiments: give the rows of at least one"),
        ("[grid]\naction_prior = ['scenario']\n", "'scenario' needs [scenario.Action] weights"),
        ("[grid]\nviewpoints = []\n", "grid.viewpoints: give at least one viewpoint"),
        ("[grid]\nnoise = 0.1\n", "grid.noise must be a list, e.g. noise = [ … ]"),
        ("[grid]\nfractions = [0.5, 0.5]\n", "fractions [0.5, 0.5]: each may appear once"),
        ("grid = 3\n", "grid must be a table ([grid])"),
        ("[views]\nleft = 3\n", "views.left must be a table, e.g. [views.left] yaw_deg = 30.0"),
        ("[views.left]\nposture = 'lying'\n", "views.left.posture='lying'; allowed: standing, seated"),
        ("[views.left]\nyaw_deg = 'north'\n", "views.left.yaw_deg='north': must be a number"),
        ("[views.left]\nmirror = 1\n", "views.left.mirror=1: must be true or false"),
        ("[recognizer]\nnoise = -0.1\n", "recognizer.noise=-0.1: the training noise must be a number ≥ 0"),
        ("[recognizer]\nfile = 3\n", "recognizer.file must be a path (a string)"),
        (
            "recognizer_seeds = 1\n[grid]\nfeatures = ['raw', 'body']\n[recognizer]\nfile = 'r.json'\n",
            "one recogniser from a file has one feature set (grid.features)",
        ),
        ("[network]\ndata = 3\n", "network.data must be a folder (a string) or 'synthetic'"),
        ("[network]\nunseen_words = 'guess'\n", "network.unseen_words='guess'; allowed: zero"),
        ("[evaluation]\nbins = 0\n", "bins=0: a whole number from 1 to 100"),
        ("[evaluation]\nlog_floor = 2\n", "log_floor=2: a number in (0, 1)"),
    ],
)
def test_bad_settings_are_one_line(tmp_path, capsys, toml, message):
    cfg = tmp_path / "small.toml"
    cfg.write_text(toml)
    status, out, err = run(capsys, "evaluate", "--config", str(cfg), "-o", str(tmp_path / "out"))
    assert status == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert message in err and str(cfg) in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--episodes", "0"], "expected a whole number ≥ 1"),
        (["--seed", "-1"], "a seed is a whole number in [0, 2**32 - 1]"),
        (["--scheduler", "localhost"], "expected a Dask scheduler address such as tcp://127.0.0.1:8786"),
        (["--config", "nope.toml"], "nope.toml: no such sweep file"),
    ],
)
def test_bad_arguments_are_one_line(tmp_path, capsys, argv, message):
    status, out, err = run(capsys, "evaluate", *argv, "-o", str(tmp_path / "out"))
    assert status == 2 and "Traceback" not in err and message in err, err
    assert not (tmp_path / "out").exists()


def test_a_view_defined_in_the_file():
    """A ``[views.NAME]`` table defines a viewpoint the grid can name, with the defaults of what it omits."""
    from glu.gestures.views import View

    c = config_from_dict(
        {"grid": {"viewpoints": ["left", "front"]}, "views": {"left": {"yaw_deg": 30, "posture": "seated"}}}
    )
    assert c.viewpoints == ("left", "front")
    assert c.views["left"] == View(yaw_deg=30, posture="seated")
    assert c.views["front"] == config_from_dict({}).views["front"]


def test_the_defaults_are_valid_and_overridable():
    c = config_from_dict({})
    # 2 worlds × 2 action priors × 4 noise levels × 4 viewpoints
    assert len(c.conditions) == 64 and c.recognizer_seeds == 10 and c.per_condition == 188
    assert len(c.readings) == 48  # (generating + 3 learned) × 4 readings of p_HMM × 3 feature sets
    assert c.with_overrides(episodes=1280, seed=None).per_condition == 2


def test_the_notebooks_defaults_are_the_saved_sweep_file():
    """sweeps/11_corpus_evaluation/sweep.toml is notebook 11's default grid (the saved tables' key)."""
    from glu.paths import PROJECT_ROOT
    from glu.run.parameters import read_spec

    spec = {
        k: p.default for k, p in read_spec(PROJECT_ROOT / "notebooks" / "11_corpus_evaluation.py").items()
    }
    saved = load_config(PROJECT_ROOT / "sweeps" / "11_corpus_evaluation" / "sweep.toml")
    notebook = config_from_parameters(spec, "DATA").as_dict()
    assert notebook.pop("network")["data"] == "DATA"
    expected = saved.as_dict()
    expected.pop("network")
    assert notebook == expected


def test_the_sweep_settings_hold_one_training_config():
    """The recogniser's [recognizer] training keys become one TrainingConfig; a field left at glu's default
    stays out of the settings' plain data (saved sweeps keep their fingerprints), a changed one is in it."""
    from glu.hmm import TrainingConfig

    config = config_from_parameters({"n_states": 4, "tol": 1e-3, "feature_sets": ["body"], "x": 1}, None)
    assert config.recognizer.training == TrainingConfig(n_states=4, tol=1e-3)
    assert config.features == ("body",)
    plain = config.as_dict()["recognizer"]
    assert (plain["n_states"], plain["tol"]) == (4, 1e-3) and "covar_reg" not in plain
    with pytest.raises(DataError, match="recognizer: unknown training recipe 'nope'"):
        config_from_parameters({"recipe": "nope"}, None)


def test_saved_tables_are_found_by_their_key(synchronous, tmp_path, monkeypatch):
    """glu evaluate --save writes the subset the notebook reads with its key; the key finds it, other
    settings do not; a computation of other settings lands in the cache with the code's digest."""
    from glu import saved
    from glu.studies.corpus_evaluation.sweep import NOTEBOOK, export_saved, saved_key
    from glu.studies.corpus_evaluation.tables import read_tables

    ref, result = synchronous
    dest = export_saved(ref, tmp_path / "sweeps" / NOTEBOOK / "synthetic", "glu evaluate --save …")
    doc = saved.read_key(dest)
    assert doc["command"] == "glu evaluate --save …" and doc["made_with"]["glu"]
    tables = read_tables(dest)
    assert len(tables.metrics) < len(result.metrics) and set(tables.metrics.metric) == {
        "accuracy",
        "log_loss",
        "ece",
    }
    assert "overall" not in tables.summary and tables.summary["data_source"] == result.summary["data_source"]
    cfg = load_config_text(SMALL)
    assert saved.find(NOTEBOOK, saved_key(cfg), [tmp_path / "sweeps" / NOTEBOOK]) == dest
    other = cfg.with_overrides(seed=4)
    assert saved.find(NOTEBOOK, saved_key(other), [tmp_path / "sweeps" / NOTEBOOK]) is None
    assert saved.cache_folder(NOTEBOOK, saved_key(other)) != saved.cache_folder(NOTEBOOK, saved_key(cfg))
    assert saved.digest(saved.cache_key(saved_key(cfg))) != saved.digest(saved_key(cfg))


def test_a_sweep_the_notebook_computed_is_found_in_the_cache(tmp_path, monkeypatch):
    """notebook_tables runs a sweep of unsaved settings into the cache once, with the key and the code's
    digest; asked again, it finds it there and runs nothing (the sweep itself stands in here)."""
    import dataclasses

    from glu import saved
    from glu.studies.corpus_evaluation import sweep

    here = dataclasses.replace(saved.HERE, saved=tmp_path / "sweeps", sweeps=tmp_path / "cache")
    monkeypatch.setattr(saved, "HERE", here)
    runs = []
    monkeypatch.setattr(
        sweep, "run_sweep", lambda config, out, **kw: runs.append(out) or out.mkdir(parents=True)
    )
    config = load_config_text(SMALL)
    first = sweep.notebook_tables(config)
    assert runs == [first] and first.parent == tmp_path / "cache" / sweep.NOTEBOOK
    assert saved.read_key(first)["key"] == saved.cache_key(sweep.saved_key(config))
    assert sweep.notebook_tables(config) == first and runs == [first]


def _shrink(folder: Path) -> None:
    """Make the tables in ``folder`` those of an older computation: one row each, a mark in the summary."""
    import json

    for name in TABLES[:-1]:
        pd.read_parquet(folder / name).head(1).to_parquet(folder / name, index=False)
    summary = json.loads((folder / "summary.json").read_text())
    (folder / "summary.json").write_text(json.dumps({**summary, "older": True}))


def _shrunk(tables) -> bool:
    """Whether ``tables`` (read back) are all of the older computation :func:`_shrink` made."""
    return all(len(df) == 1 for df in tables[:5]) and tables.summary.get("older") is True


def test_a_rewrite_of_saved_tables_cut_short_is_refused_never_mixed(synchronous, tmp_path):
    """glu evaluate --save over saved tables of an older computation, interrupted after the first table:
    the folder is refused in one line and passed by when looking for its key, never read as the new table
    beside the old ones; a file of the user's in it survives, and a complete write is read whole."""
    from cut_short import cut_short, old_or_refused

    from glu import saved
    from glu.studies.corpus_evaluation.sweep import NOTEBOOK, export_saved
    from glu.studies.corpus_evaluation.tables import read_tables

    ref, _ = synchronous
    root = tmp_path / "sweeps" / NOTEBOOK
    dest = root / "synthetic"
    dest.mkdir(parents=True)
    (dest / "notes.txt").write_text("mine\n")
    export_saved(ref, dest, "glu evaluate --save …")
    key = saved.read_key(dest)["key"]
    _shrink(dest)
    assert saved.find(NOTEBOOK, key, [root]) == dest and _shrunk(read_tables(dest))
    with cut_short(pd.DataFrame, "to_parquet", at=2):
        export_saved(ref, dest, "glu evaluate --save …")
    refusal = old_or_refused(lambda: read_tables(dest), _shrunk)
    assert refusal is not None and "not the output folder of a finished `glu evaluate`" in refusal
    assert saved.find(NOTEBOOK, key, [root]) is None
    assert (dest / "notes.txt").read_text() == "mine\n"
    export_saved(ref, dest, "glu evaluate --save …")
    assert saved.find(NOTEBOOK, key, [root]) == dest and not _shrunk(read_tables(dest))
    assert (dest / "notes.txt").read_text() == "mine\n"


def test_a_rewrite_of_a_sweeps_tables_cut_short_is_refused_never_mixed(config_file, synchronous, tmp_path):
    """A finished sweep whose tables are an older computation's, run again and interrupted after its first
    table: the folder is refused in one line (no summary.json), never read as the new table beside the old
    ones; a file of the user's in it survives, and the run completed writes the same tables as the first."""
    from cut_short import cut_short, old_or_refused

    from glu.studies.corpus_evaluation.tables import read_tables

    ref, _ = synchronous
    out = tmp_path / "again"
    shutil.copytree(ref, out)
    (out / "notes.txt").write_text("mine\n")
    _shrink(out)
    with cut_short(pd.DataFrame, "to_parquet", at=2):
        run_sweep(load_config(config_file), out, scheduler="synchronous", log=quiet)
    refusal = old_or_refused(lambda: read_tables(out), _shrunk)
    assert refusal is not None and "not the output folder of a finished `glu evaluate`" in refusal
    assert (out / "notes.txt").read_text() == "mine\n"
    run_sweep(load_config(config_file), out, scheduler="synchronous", log=quiet)
    same_tables(ref, out)
    assert (out / "summary.csv").read_bytes() == (ref / "summary.csv").read_bytes()
    assert (out / "notes.txt").read_text() == "mine\n"


def load_config_text(text: str):
    import tomllib

    return config_from_dict(tomllib.loads(text))


def test_glu_corpus_writes_parquet(config_file, tmp_path, capsys):
    status, out, err = run(
        capsys, "corpus", "--config", str(config_file), "--episodes", "16", "-o", str(tmp_path / "c.parquet")
    )
    assert status == 0, err
    df = pd.read_parquet(tmp_path / "c.parquet")
    assert len(df) == 16 and {"Action", "ObjVel", "words", "xyz", "noise", "viewpoint", "replication"} <= set(
        df.columns
    )
    assert set(df.replication) == {0, 1}


def test_readings_share_the_episodes(config_file, synchronous, tmp_path):
    """Another reading of p_HMM is scored on the same episodes: the other readings' rows are unchanged."""
    ref, _ = synchronous
    config = load_config(config_file).with_overrides(p_hmm=("likelihood", "per-frame", "calibrated"))
    result = run_sweep(config, tmp_path, scheduler="synchronous", log=quiet)
    assert set(result.metrics.p_hmm) == {"likelihood", "per-frame", "calibrated"}
    one = pd.read_parquet(ref / "results.parquet")
    both = result.metrics[result.metrics.p_hmm != "per-frame"]
    key = ["inference_network", "p_hmm", "noise", "viewpoint", "target", "strategy", "fraction", "metric"]
    both = both.set_index(key).sort_index()
    one = one.set_index(key).sort_index()
    pd.testing.assert_series_equal(both.estimate, one.estimate, check_exact=True)
    assert result.summary["episodes"] == 64


def test_the_notebook_reads_a_finished_sweep(synchronous):
    from glu.studies.corpus_evaluation.tables import read_tables

    out, result = synchronous
    table, diffs, rel, seeds, calibration, summary = read_tables(out)
    pd.testing.assert_frame_equal(table, result.metrics)
    assert summary["fingerprint"] == result.summary["fingerprint"]
    with pytest.raises(DataError, match="not the output folder of a finished"):
        read_tables(out / "chunks")


@pytest.mark.slow
def test_a_finished_sweep_run_again_computes_nothing(config_file, synchronous, tmp_path):
    """Run again, a finished sweep reuses every chunk and writes the same tables."""
    ref, first = synchronous
    dest = tmp_path / "again"
    shutil.copytree(ref, dest)
    result = run_sweep(load_config(config_file), dest, scheduler="synchronous", log=quiet)
    assert result.computed == 0 and result.reused == first.computed + first.reused
    pd.testing.assert_frame_equal(result.metrics, first.metrics)


def test_unreadable_or_foreign_files_in_a_sweep_folder_are_one_error(config_file, synchronous, tmp_path):
    """An unreadable sweep.json, a chunk of another sweep, a summary of another experiment: each is refused
    with the file named, nothing computed."""
    from glu.studies.corpus_evaluation.tables import chunk_path, read_chunk, read_tables

    ref, _ = synchronous
    dest = tmp_path / "copy"
    shutil.copytree(ref, dest)
    (dest / "sweep.json").write_text("{", encoding="utf-8")
    with pytest.raises(DataError, match="holds a sweep with other settings or data \\(sweep.json\\)"):
        run_sweep(load_config(config_file), dest, scheduler="synchronous", log=quiet)
    chunk = chunk_path(ref, 0, 0)
    with pytest.raises(DataError, match=f"{chunk.name}: this chunk belongs to another sweep"):
        read_chunk(chunk, "another fingerprint")
    summary = dest / "summary.json"
    summary.write_text(summary.read_text().replace('"corpus_evaluation"', '"learning_curves"'))
    with pytest.raises(DataError, match="summary.json is not a corpus evaluation's"):
        read_tables(dest)


def test_the_saved_settings_name_no_folder_of_this_machine():
    from glu.studies.corpus_evaluation.sweep import _public

    settings = {
        "network": {"data": "/home/me/data/real"},
        "recognizer": {"file": "/tmp/x/rec.json"},
        "seed": 1,
    }
    assert _public(settings) == {"network": {"data": "real"}, "recognizer": {"file": "rec.json"}, "seed": 1}
    same = {"network": {"data": "synthetic"}, "recognizer": {"file": None}}
    assert _public(same) == same


class _Future:
    def __init__(self, error):
        self.error, self.cancelled = error, False

    def result(self):
        raise self.error

    def cancel(self):
        self.cancelled = True


@pytest.mark.parametrize(
    ("error", "raised", "message"),
    [
        (DataError("bad gesture"), DataError, "bad gesture"),
        (
            "KilledWorker",
            "WorkerLostError",
            "a Dask worker was lost .*\\(KilledWorker\\); the chunks finished",
        ),
        (ImportError("no module glu"), RuntimeError, "a sweep task failed on the cluster \\(ImportError: no"),
    ],
)
def test_a_failed_task_on_the_cluster_is_said_in_one_line(monkeypatch, tmp_path, error, raised, message):
    """A task's bad input is raised as it is; a worker that died, as a lost worker (the finished chunks kept);
    anything else names the exception; the other tasks are cancelled."""
    import contextlib

    import distributed
    from distributed.scheduler import KilledWorker

    from glu.studies.corpus_evaluation import sweep

    if error == "KilledWorker":
        error = KilledWorker("glu-chunk-0", None, 3)
    raised = sweep.WorkerLostError if raised == "WorkerLostError" else raised
    futures = []

    class Client:
        def submit(self, *args, **kwargs):
            futures.append(_Future(error))
            return futures[-1]

    monkeypatch.setattr(sweep, "dask_client", lambda *a, **k: contextlib.nullcontext(Client()))
    monkeypatch.setattr(distributed, "as_completed", iter)
    with pytest.raises(raised, match=message):
        sweep._run_on_dask(None, [(0, None, 0, 4), (0, None, 1, 4)], tmp_path, "f" * 16, None, 1, None)
    cancelled = [f.cancelled for f in futures[1:]]  # the first is the shared evaluator
    assert cancelled == [not isinstance(error, DataError)] * 2


ONE_SEED = SMALL.replace("recognizer_seeds = 2", "recognizer_seeds = 1").replace(
    'inference_network = ["generating", "learned"]', 'inference_network = ["generating"]'
)


@pytest.mark.slow
def test_a_recogniser_file_and_a_damaged_saved_recogniser(tmp_path):
    """A sweep given its own saved recogniser as ``[recognizer] file`` computes the tables it computed; a
    saved recogniser that cannot be read is trained again (the same file); one lacking an action is
    refused."""
    from glu.gestures.recognizer import Recognizer

    config = load_config_text(ONE_SEED)
    first = run_sweep(config, tmp_path / "a", scheduler="synchronous", log=quiet)
    saved = tmp_path / "a" / "recognizers" / "seed-000-raw.json"
    original = saved.read_bytes()
    rec = replace(config.recognizer, file=str(saved))
    from_file = run_sweep(
        config.with_overrides(recognizer=rec), tmp_path / "b", scheduler="synchronous", log=quiet
    )
    pd.testing.assert_frame_equal(from_file.metrics, first.metrics)
    assert not (tmp_path / "b" / "recognizers").exists()
    saved.write_text("{", encoding="utf-8")  # cut short
    again = run_sweep(config, tmp_path / "a", scheduler="synchronous", log=quiet)
    assert again.computed == 0 and saved.read_bytes() == original
    full = Recognizer.load(saved)
    Recognizer({a: full.models[a] for a in ("grasp", "tap")}).save(tmp_path / "two.json")
    rec = replace(config.recognizer, file=str(tmp_path / "two.json"))
    with pytest.raises(ModelError, match="the recogniser has no model for touch; it needs grasp, tap, touch"):
        run_sweep(config.with_overrides(recognizer=rec), tmp_path / "c", scheduler="synchronous", log=quiet)
    assert not (tmp_path / "c").exists()


def test_matched_gestures_with_fewer_gestures_than_views_and_no_learned_network():
    """3 held-out gestures over 4 (viewpoint, noise) pairs: gesture i is seen from pair i, the fourth pair
    sees none; a sweep of the generating network learns none."""
    from glu.gestures.synthetic_batch import gesture_features
    from glu.studies.corpus_evaluation import robots
    from glu.studies.corpus_evaluation.sweep import prepare_world

    config = load_config_text(ONE_SEED.replace("calibration_per_action = 4", "calibration_per_action = 1"))
    xs, actions = robots.matched_gestures(config, 0, False)
    assert actions.tolist() == [0, 1, 2]
    pairs = [(v, x) for v in config.viewpoints for x in config.noise]
    for i, (view, noise) in enumerate(pairs[:3]):
        one = gesture_features(
            [robots.ACTIONS[i]],
            [np.random.default_rng([config.seed, robots.MATCHED_KEY, 0, i])],
            noise=noise,
            spike_rate=config.gestures.spike_rate,
            dropout_rate=config.gestures.dropout_rate,
            view=config.views[view],
        )
        np.testing.assert_array_equal(xs[i], one.features[0])
    engine, _ = prepare_world(config)
    assert robots.learned_networks(config, engine) == [{}]


@pytest.mark.slow
def test_glu_evaluate_save_writes_the_saved_tables_with_the_command(
    synchronous, config_file, tmp_path, capsys, monkeypatch
):
    """A finished sweep run again with --save: every chunk reused, the subset notebook 11 reads written
    with the command that makes it (no path of this machine: an absolute path is …/NAME)."""
    from glu import saved

    ref, _ = synchronous
    out, dest = tmp_path / "ev", tmp_path / "saved"
    shutil.copytree(ref, out)
    argv = ["evaluate", "--config", str(config_file), "--scheduler", "synchronous", "-o", str(out)]
    monkeypatch.setattr(sys, "argv", ["glu", *argv, "--save", str(dest)])
    status, stdout, err = run(capsys, *argv, "--save", str(dest))
    assert status == 0, err
    assert stdout.startswith("0 chunks computed, 8 reused") and stdout.endswith(f"saved tables → {dest}\n")
    assert saved.read_key(dest)["command"] == (
        "glu evaluate --config '…/small.toml' --scheduler synchronous -o '…/ev' --save '…/saved'"
    )
    assert (dest / "results.parquet").is_file()
