"""The first call of every notebook: check its parameters, name its data, say where its outputs go.

A notebook's first code cell after its parameters is ::

    from glu.run.notebook import start
    out = start("07_glu2017_figures", globals())

:func:`start` checks the parameters against the notebook's own declaration (:mod:`glu.run.parameters`) —
including names that papermill injected but the notebook does not declare — so a run by hand, by plain
papermill or by ``glu run`` fails at once, in one line, instead of after minutes of work. It resolves the
data the same way from any working directory, shows one line naming the data (and why, when it fell
back to synthetic data) and the non-default parameters, and returns the :class:`glu.run.outputs.Outputs` of
the run: the staging folder ``glu reproduce`` passed as ``out_dir``, or for any other run a new folder of
its own in the notebook's scratch folder (``build/scratch/<notebook>/<date>-<time>/``: no run overwrites
another's outputs), so only ``glu reproduce`` publishes into ``results/``, ``recordings/``, ``models/``.
From then on, a cell that ends with a DataFrame shows it as :func:`glu.tidy.html_table` writes it:
rounded for reading, whole on the page.
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from glu import paths
from glu.data.source import resolve_data
from glu.machine import in_kernel
from glu.paths import OutputLayout
from glu.run.outputs import Outputs, parameters_text
from glu.run.parameters import check, non_defaults, read_spec
from glu.run.publish import refuse_published

INJECTED_COMMENT = "# Parameters"
"""The first line of the cell papermill injects after the parameters cell."""


def injected_names(namespace: Mapping[str, Any]) -> list[str]:
    """Names assigned by the parameters cell papermill injected in this kernel (none in a by-hand run).

    Read from the kernel's input history (``In``): the last executed cell that starts with papermill's
    comment ``# Parameters``.
    """
    history = namespace.get("In")
    if not isinstance(history, list):
        return []
    for source in reversed(history):
        if isinstance(source, str) and source.startswith(INJECTED_COMMENT + "\n"):
            try:
                tree = ast.parse(source)
            except SyntaxError:
                return []
            targets = (t for node in tree.body if isinstance(node, ast.Assign) for t in node.targets)
            return [t.id for t in targets if isinstance(t, ast.Name)]
    return []


def notebook_source(notebook: str) -> Path:
    """The notebook's jupytext source: ``<name>.py`` in the working directory (where papermill, JupyterLab
    and ``glu reproduce`` run a notebook), else glu's own ``notebooks/<name>.py`` (in the checkout, or
    the installed package ``glu.notebooks``)."""
    here = Path.cwd() / f"{notebook}.py"
    return here if here.is_file() else paths.notebook_file(notebook)


def start(notebook: str, namespace: Mapping[str, Any]) -> Outputs:
    """Check the parameters in ``namespace`` (a notebook's ``globals()``) and open the run's outputs.

    Raises :class:`glu.errors.ParameterError` (one line) for an undeclared name, a wrong type or a value
    outside its choices or range, and :class:`glu.errors.DataError` for a data folder that is not one.
    """
    spec = read_spec(notebook_source(notebook))
    given = {n: namespace[n] for n in spec if n in namespace}
    given.update({n: namespace.get(n) for n in injected_names(namespace) if n not in spec})
    values = check(spec, given, notebook)
    source = resolve_data(values.get("data"))
    out_dir = values.get("out_dir")
    if out_dir:
        layout = OutputLayout.at(out_dir)
        refuse_published(layout, "a notebook run by hand")
    else:
        layout = OutputLayout.scratch(notebook)
    params = non_defaults(spec, values)
    out = Outputs(notebook, source, layout, parameters=params)
    line = f"**{notebook}** · {source.describe()} ({source.reason()})"
    line += f" · parameters: {parameters_text(params)}" if params else " · default parameters"
    if not out_dir:
        where = str(layout.root)
        if paths.PROJECT_ROOT is not None:
            where = f"build/scratch/{notebook}/{layout.root.name}/"
        line += (
            f" · outputs go to a scratch folder of this run's own, {where} "
            "(only `glu reproduce` publishes to results/, recordings/, models/)"
        )
    out.say(line if in_kernel() else line.replace("**", ""))
    _show_tables()
    return out


def _show_tables() -> None:
    """In a kernel, show every DataFrame a cell ends with as :func:`glu.tidy.html_table` does: rounded for
    reading, no ``0 … n-1`` index, missing values as a dash (the result files keep every digit)."""
    if not in_kernel():
        return
    import pandas as pd
    from IPython import get_ipython

    from glu.tidy import html_table

    shell = get_ipython()
    if shell is not None:
        shell.display_formatter.formatters["text/html"].for_type(pd.DataFrame, html_table)
