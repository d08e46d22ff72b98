"""Where a notebook's outputs go, and how they are written: figures, result tables, recordings.

A notebook gets its :class:`Outputs` from :func:`glu.run.notebook.start`. It saves figures (PNG + SVG at
:data:`glu.plots.style.DPI`, deterministic, stamped with the data source and the run's non-default
parameters, and shown inline when a kernel runs the notebook), result tables (CSV + JSON, with the
experiment's provenance: data source and parameters) and gives paths for Rerun recordings and trained
models. Where each kind goes is :class:`glu.paths.OutputLayout`'s business: ``glu reproduce`` passes a
staging folder and publishes the files only when every notebook succeeded; any other run writes into a
new folder of its own in the notebook's scratch folder (``build/scratch/<notebook>/<date>-<time>/``) and
never touches the published ones.
"""

from __future__ import annotations

import json
import platform
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

import pandas as pd

from glu.data.source import DataSource
from glu.errors import OutputError
from glu.files import atomic_write_text
from glu.machine import in_kernel
from glu.paths import OutputLayout

PACKAGES = ("glu", "numpy", "scipy", "pandas", "numba", "pgmpy", "matplotlib", "rerun-sdk", "papermill")


def parameters_text(params: Mapping[str, Any]) -> str:
    """Parameters as outputs name them: ``rule=jeffrey, step=2`` (empty for none)."""
    return ", ".join(f"{k}={v}" for k, v in params.items())


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
    parameters : the run's parameters that differ from the notebook's defaults (named on every output)
    """

    notebook: str
    source: DataSource
    layout: OutputLayout
    parameters: dict[str, Any] = field(default_factory=dict)
    written: list[Path] = field(default_factory=list)

    @property
    def data_label(self) -> str:
        """One line naming the data, for figure footers and tables."""
        return self.source.describe()

    @property
    def parameters_label(self) -> str:
        """The run's non-default parameters, ``rule=jeffrey, step=2`` (empty with the defaults)."""
        return parameters_text(self.parameters)

    def footer(self, source: str | None = None) -> str:
        """What every output of this run names: its data, and its non-default parameters."""
        text = source or self.data_label  # names its origin ("real data: …", "synthetic data …")
        return text + (f" · {self.notebook} with {self.parameters_label}" if self.parameters else "")

    def figure(self, fig: Any, name: str, source: str | None = None, caption: str = "") -> None:
        """Stamp ``fig`` with :meth:`footer` and the glu that made it (its version and commit,
        :func:`glu.run.provenance.made_by`), save ``figures/<name>.png`` and ``.svg``, and show the PNG.

        In a running kernel the saved PNG itself is displayed (tagged with its file name in the output's
        metadata, ``{"glu": {"figure": "<name>.png"}}``), so the executed notebook shows exactly the file
        that was written; the figure is then closed. Returns None, so that a cell ending with it shows no
        path (the files are in :attr:`written`).

        ``caption``: what this figure shows, when its cell draws several (one sentence, Markdown; no number
        of the results). The site's caption of a figure is the title of its section, then this sentence,
        or else the prose that follows the cell (:func:`glu.run.captions.figure_captions`).
        """
        from glu.plots.style import save_figure, stamp
        from glu.run.provenance import made_by

        stamp(fig, self.footer(source), made_by())
        files = save_figure(fig, self.layout.figures / name)
        self.written.extend(files)
        import matplotlib.pyplot as plt

        plt.close(fig)
        _show_png(files[0], caption)

    def table(self, df: pd.DataFrame, name: str | None = None, **extra: Any) -> None:
        """Save the numbers behind a figure as ``results/<name>.csv`` and ``.json`` (with provenance).
        Returns None, so that a cell ending with it shows no path (the files are in :attr:`written`).

        ``name`` defaults to the frame's experiment (``df.attrs["experiment"]``); the JSON's ``meta`` holds
        the experiment, its data source and parameters (from :func:`glu.tidy.tidy`), the
        notebook, and ``extra``.
        """
        name = name or df.attrs.get("experiment")
        if not name:
            raise OutputError("a table needs a name (or an experiment frame that carries one)")
        csv = self.layout.results / f"{name}.csv"
        atomic_write_text(csv, df.to_csv(index=False, float_format="%.12g", lineterminator="\n"))
        meta = {
            "name": name,
            "notebook": self.notebook,
            "notebook_parameters": self.parameters,
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

    def say(self, text: str) -> None:
        """Show a sentence written by code from the tables: Markdown in a running kernel, plain text
        elsewhere.

        Notebook prose that names a number or a comparison goes through here (or a table), never into a
        markdown cell, so a changed result cannot leave a stale sentence.
        """
        if in_kernel():
            from IPython.display import Markdown, display

            display(Markdown(text))
        else:
            print(text)

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


def _show_png(path: Path, caption: str = "") -> None:
    """Display a saved PNG in the running kernel, at the size it has at 100 dpi (nothing outside a kernel),
    tagged with its file name and its own caption, if any."""
    if not in_kernel():
        return
    from IPython.display import Image, display

    from glu.plots.style import DPI

    data = path.read_bytes()
    width_px = int.from_bytes(data[16:20], "big")  # the PNG header's IHDR width
    image = Image(data=data, format="png", width=width_px * 100 // DPI)
    display(image, metadata={"glu": {"figure": path.name, **({"caption": caption} if caption else {})}})
