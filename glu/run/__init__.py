"""The notebook runner: how the story's notebooks are run, checked, collected and published.

One module per concern, in the order a run meets them:

* :mod:`~glu.run.manifest` — what each notebook declares in its header: its figures, tables, recordings and
  models, its quick preset, its expected seconds (the one place these are written);
* :mod:`~glu.run.parameters` — the parameters cell of a notebook, read and checked;
* :mod:`~glu.run.notebook` — :func:`start`, the first call of every notebook (data, parameters, outputs);
* :mod:`~glu.run.outputs` — where a notebook's figures, tables, recordings and models are written;
* :mod:`~glu.run.execution` — one notebook executed headless with papermill, stoppable at once;
* :mod:`~glu.run.reproduce` — every notebook, two at a time, all-or-nothing publication;
* :mod:`~glu.run.summary` — ``results/summary.json`` and ``.csv`` from the notebooks' tables;
* :mod:`~glu.run.site` — the documentation site of a run (Sphinx, MyST-NB), its figures captioned by
  :mod:`~glu.run.captions`;
* :mod:`~glu.run.readme` — the README's results section, from ``results/summary.json``;
* :mod:`~glu.run.generated` — the pages' other generated sections (the README's story table, from the
  manifests), and :mod:`~glu.run.speed` — the speed page's tables, from the benchmarks' results.

The science is below, in :mod:`glu.studies` (one package per study) and the library under it; the runner
knows no study by name: the README's results section and the parameters' choices come from the studies'
own declarations (:func:`glu.studies.readme_parts`, :func:`glu.studies.parameter_choices`), and nothing here
computes a number of the papers.
"""

from glu.run.notebook import start

__all__ = ["start"]
