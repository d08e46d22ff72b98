"""Corpus sweeps: the settings (:mod:`~glu.sweep.config`) and running them on Dask (:mod:`~glu.sweep.runner`).

``glu evaluate`` is a thin wrapper over :func:`run_sweep`; notebook 11 calls it with
``scheduler="synchronous"``.
"""

from glu.sweep.config import SweepConfig, config_from_dict, load_config
from glu.sweep.runner import SweepResult, check_scheduler, run_sweep

__all__ = ["SweepConfig", "SweepResult", "check_scheduler", "config_from_dict", "load_config", "run_sweep"]
