"""Shared fixtures: data sources for the oracle tests, and the real data for the reference tests.

Two kinds of tests use data:

* **oracle tests** compare glu with an independent reference (pgmpy, hmmlearn, brute force, closed forms)
  on whatever data there is. They take the ``source`` fixture (or a fixture built on it), which runs them
  on a synthetic data folder always, and also on the real data when it is present (CI). Without the real
  data they still run, on synthetic data.
* **reference tests** (``tests/studies/test_reference*.py``,
  ``tests/studies/test_correspondence_reference.py``) compare glu with the originals' models and the published
  numbers; they need the real data and skip with a reason without it. Each covers one published artefact, its
  parts as subtests, so that a clone without the data skips nine tests.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("RERUN_ANALYTICS", "0")
os.environ.setdefault("MPLBACKEND", "Agg")

from glu.paths import shared_data_dir  # noqa: E402
from glu.run.execution import load_papermill  # noqa: E402

load_papermill()  # jsonschema as glu reproduce loads it, without the optional IRI checker nbformat never asks
# for, which builds 38 grammars at import: collecting the suite took 22-25 s with it, 16 s without

SHARED = shared_data_dir()
NO_SHARED_REASON = (
    "the real data is absent: set GLU_SHARED_DATA, place it in ../shared/data (CI has it), "
    "or download it with `glu data fetch` (to data/real/)"
)
SOURCES = ("synthetic", "real") if SHARED is not None else ("synthetic",)
"""The data the oracle tests run on: synthetic always, real when present (never a skipped instance)."""
SYNTHETIC_SEED = 0
SYNTHETIC_N = 1270


@pytest.fixture(scope="session", autouse=True)
def _temporary_files_under_pytests_folder(tmp_path_factory):
    """Every temporary file of the session (the docstring examples' ``tempfile.mkdtemp()``, Dask's scratch
    space, kernels, browsers, subprocesses) goes under pytest's own folder, which pytest prunes, instead of
    piling up in the system's temporary folder run after run."""
    import tempfile

    folder = tmp_path_factory.mktemp("tmp")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("TMPDIR", str(folder))
        patch.setattr(tempfile, "tempdir", str(folder))
        yield folder


# ---------------------------------------------------------------- any data (oracle tests)
@pytest.fixture(scope="session")
def synthetic_folder(tmp_path_factory) -> Path:
    """A synthetic data folder, as ``glu data synth`` writes it: both tables and the six hand logs."""
    from glu.data.synthetic import write_synthetic_folder
    from glu.gestures.corpus import hand_log_arrays, synthetic_recordings

    out = tmp_path_factory.mktemp("synthetic-data")
    logs = {name: hand_log_arrays(g) for name, g in synthetic_recordings(SYNTHETIC_SEED).items()}
    return write_synthetic_folder(out, SYNTHETIC_N, SYNTHETIC_SEED, logs)


@pytest.fixture(scope="session", params=SOURCES)
def source(request, synthetic_folder):
    """A data source: the synthetic folder, and (a second instance) the real data when present."""
    from glu.data import resolve_data

    return resolve_data(SHARED if request.param == "real" else synthetic_folder)


@pytest.fixture(scope="session")
def table(source):
    """The source's experiment table (words from transcriptions)."""
    from glu.data import load_experiments

    return load_experiments(source, "lab")


@pytest.fixture(scope="session")
def zero_bn(table):
    """The network learned faithfully: all-zero CPT rows for word parent configurations never seen."""
    from glu.bn import learn_bn

    return learn_bn(table)


@pytest.fixture(scope="session")
def uniform_bn(table):
    """The network learned with uniform rows for unseen word parent configurations."""
    from glu.bn import learn_bn

    return learn_bn(table, unseen_words="uniform")


@pytest.fixture(scope="session")
def recognizer(source):
    """Gesture HMMs for the source: the originals' 2013 models on real data, small glu-trained ones
    otherwise."""
    from glu.gestures.corpus import gesture_sequences
    from glu.gestures.recognizer import load_original_models
    from glu.hmm import TrainingConfig
    from glu.studies.replication.gestures import train_on

    if source.original_hmms() is not None:
        return load_original_models(source.original_hmms())
    return train_on(
        gesture_sequences(source, include_test=False), TrainingConfig(n_states=4, n_mix=1, n_iter=20)
    )


# ---------------------------------------------------------------- the real data (reference tests)
@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The folder with the real data (affordance-words/, gestures/, reference-models/), or skip."""
    if SHARED is None:
        pytest.skip(NO_SHARED_REASON)
    return SHARED


@pytest.fixture(scope="session")
def real_source(shared_data):
    """The real data as a :class:`glu.data.DataSource`."""
    from glu.data import resolve_data

    return resolve_data(shared_data)


@pytest.fixture(scope="session")
def lab_table(real_source):
    """The paper's experiment table (words from transcriptions), validated."""
    from glu.data import load_experiments

    return load_experiments(real_source, "lab")


@pytest.fixture(scope="session")
def original_bn(real_source):
    """The authors' learned network, imported from BN_lab.mat."""
    from glu.bn import BayesNet

    return BayesNet.from_bnt_mat(real_source.original_bn())


@pytest.fixture(scope="session")
def learned_bn(lab_table):
    """The network glu learns from the lab table (faithful default: zero rows for unseen word parents)."""
    from glu.bn import learn_bn

    return learn_bn(lab_table)


# ---------------------------------------------------------------- the machine's /dev/null
def _dev_null_is_a_device() -> bool:
    import stat

    try:
        return stat.S_ISCHR(os.stat("/dev/null").st_mode)
    except OSError:
        return False


def pytest_sessionstart(session):
    session.config._dev_null_at_start = _dev_null_is_a_device()


def pytest_sessionfinish(session, exitstatus):
    """Fail the run if ``/dev/null`` was a character device when it started and is not one now (a writer
    renaming a file over a device, issue 26). When it was already broken, say so without failing."""
    if _dev_null_is_a_device():
        return
    if getattr(session.config, "_dev_null_at_start", True):
        print("\nERROR: /dev/null is no longer a character device: a test or a glu writer replaced it")
        session.exitstatus = 1
    else:
        print("\nwarning: /dev/null was not a character device when the tests started (replaced before)")
