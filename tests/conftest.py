"""Shared fixtures: the real data (skipped with a reason when absent) and small synthetic models."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("RERUN_ANALYTICS", "0")
os.environ.setdefault("MPLBACKEND", "Agg")

from glu.paths import shared_data_dir  # noqa: E402

SHARED = shared_data_dir()
NO_SHARED_REASON = (
    "the real data is absent: set GLU_SHARED_DATA or place it in ../shared/data (CI has it); "
    "`glu data fetch` downloads it"
)


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
def lab_table(shared_data):
    """The paper's experiment table (words from transcriptions), validated."""
    from glu.data import load_experiments

    return load_experiments(shared_data, "lab")


@pytest.fixture(scope="session")
def original_bn(shared_data):
    """The authors' learned network, imported from BN_lab.mat."""
    from glu.bn import BayesNet

    return BayesNet.from_bnt_mat(shared_data / "reference-models" / "BN_lab.mat")


@pytest.fixture(scope="session")
def learned_bn(lab_table):
    """The network glu learns from the lab table (faithful default: zero rows for unseen word parents)."""
    from glu.bn import learn_bn

    return learn_bn(lab_table)
