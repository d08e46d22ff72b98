"""Where a notebook's outputs go, and how they are written: figures, result tables, recordings.

A notebook calls :func:`open_outputs` once with its parameters; the returned :class:`Outputs` saves
figures (PNG + SVG, deterministic, stamped with the data source), result tables (CSV + JSON, with the
experiment's provenance: data source and parameters) and gives paths for Rerun recordings and trained
models. Where each kind goes is :class:`glu.paths.OutputLayout`'s business: with ``out_dir=None`` the
project's ``figures/``, ``results/``, ``recordings/`` and ``models/``; ``glu reproduce`` passes a staging
folder and publishes the files only when the notebook succeeds.
"""

from __future__ import annotations

import json
import os
import platform
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

import pandas as pd

from glu.data.source import DataSource, resolve_data
from glu.files import atomic_write_text
from glu.paths import OutputLayout

PACKAGES = ("glu", "numpy", "scipy", "pandas", "pgmpy", "hmmlearn", "matplotlib", "rerun-sdk", "papermill")


def package_versions() -> dict[str, str]:
    """Versions of Python and of the packages behind the results."""
    out = {"python": platform.python_version()}
    for name in PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


@dataclass
class Outputs:
    """Output folders of one notebook run, and the data source it used.

    Attributes
    ----------
    notebook : the notebook's name (e.g. ``"03_bn_learning"``), recorded with every table
    source : the resolved data source
    layout : where each kind of output goes (folders are created on first use)
    """

    notebook: str
    source: DataSource
    layout: OutputLayout
    written: list[Path] = field(default_factory=list)

    @property
    def figures(self) -> Path:
        """The folder of figures."""
        return self.layout.figures

    @property
    def results(self) -> Path:
        """The folder of result tables."""
        return self.layout.results

    @property
    def data_label(self) -> str:
        """One line naming the data, for figure footers and tables."""
        return self.source.describe()

    def figure(self, fig: Any, name: str, source: str | None = None) -> list[Path]:
        """Stamp ``fig`` with the data source and save it as ``figures/<name>.png`` and ``.svg``."""
        from glu.plots.style import save_figure, stamp

        stamp(fig, source or self.data_label)
        files = save_figure(fig, self.layout.figures / name)
        self.written.extend(files)
        import matplotlib.pyplot as plt

        plt.close(fig)
        return files

    def table(self, df: pd.DataFrame, name: str | None = None, **extra: Any) -> Path:
        """Save the numbers behind a figure as ``results/<name>.csv`` and ``.json`` (with provenance).

        ``name`` defaults to the frame's experiment (``df.attrs["experiment"]``); the JSON's ``meta`` holds
        the experiment, its data source and parameters (from :func:`glu.experiments.common.tidy`), the
        notebook, and ``extra``.
        """
        name = name or df.attrs.get("experiment")
        if not name:
            raise ValueError("a table needs a name (or an experiment frame that carries one)")
        csv = self.layout.results / f"{name}.csv"
        atomic_write_text(csv, df.to_csv(index=False, float_format="%.12g", lineterminator="\n"))
        meta = {
            "name": name,
            "notebook": self.notebook,
            "data_source": df.attrs.get("data_source", self.data_label),
            "data": self.data_label,
            **({"experiment": df.attrs["experiment"]} if "experiment" in df.attrs else {}),
            **({"parameters": df.attrs["parameters"]} if df.attrs.get("parameters") else {}),
            **extra,
        }
        doc = {"meta": meta, "rows": json.loads(df.to_json(orient="records", double_precision=15))}
        js = self.layout.results / f"{name}.json"
        atomic_write_text(js, json.dumps(doc, indent=1, sort_keys=False) + "\n")
        self.written.extend([csv, js])
        return csv

    def model(self, name: str) -> Path:
        """Path for a trained model file ``models/<name>`` (the folder is created)."""
        self.layout.models.mkdir(parents=True, exist_ok=True)
        p = self.layout.models / name
        self.written.append(p)
        return p

    def recording(self, name: str) -> Path:
        """Path for a Rerun recording ``recordings/<name>.rrd`` (the folder is created)."""
        self.layout.recordings.mkdir(parents=True, exist_ok=True)
        p = self.layout.recordings / f"{name}.rrd"
        self.written.append(p)
        return p


def open_outputs(
    notebook: str, data: str | os.PathLike | None = None, out_dir: str | os.PathLike | None = None
) -> Outputs:
    """Resolve the data source and the output folders for a notebook run.

    Parameters
    ----------
    notebook : the notebook's name
    data : data folder, ``"synthetic"``, or None (``$GLU_DATA_DIR``, ``data/real/``, else synthetic)
    out_dir : folder for ``figures/``, ``results/``, ``recordings/``; None = the project's own folders
    """
    source = resolve_data(data)
    print(f"{notebook}: {source.describe()}")
    return Outputs(notebook, source, OutputLayout.at(out_dir))
