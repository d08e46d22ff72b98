"""Where glu's inputs and outputs live, rooted at the project (never at the working directory)."""

from __future__ import annotations

import os
from pathlib import Path

PACKAGE_DIR: Path = Path(__file__).resolve().parent
PROJECT_ROOT: Path = PACKAGE_DIR.parent
RESOURCES_DIR: Path = PACKAGE_DIR / "resources"

DATA_DIR: Path = PROJECT_ROOT / "data"
REAL_DATA_DIR: Path = DATA_DIR / "real"
FIGURES_DIR: Path = PROJECT_ROOT / "figures"
RECORDINGS_DIR: Path = PROJECT_ROOT / "recordings"
RESULTS_DIR: Path = PROJECT_ROOT / "results"
MODELS_DIR: Path = PROJECT_ROOT / "models"
EXECUTED_DIR: Path = PROJECT_ROOT / "build" / "notebooks"
NOTEBOOKS_DIR: Path = PROJECT_ROOT / "notebooks"

DATA_ENV_VAR = "GLU_DATA_DIR"


def shared_data_dir() -> Path | None:
    """Return the shared copy of the real data used by tests and CI (``GLU_SHARED_DATA`` or ``../shared/data``)."""
    env = os.environ.get("GLU_SHARED_DATA")
    candidates = [Path(env)] if env else []
    candidates.append(PROJECT_ROOT.parent / "shared" / "data")
    for c in candidates:
        if (c / "affordance-words").is_dir():
            return c.resolve()
    return None
