"""The studies: one package per story the notebooks tell, between the library below and the runner above.

Each study holds its experiments (functions returning tidy frames stamped with their provenance,
:func:`glu.tidy.tidy`), its figures, its recordings, the sentences written from its tables, and the
README's bullets about it (its ``readme`` module):

* :mod:`~glu.studies.replication` — notebooks 01–07 and 09: the gesture HMMs, the Affordance–Words network,
  fusion and verbal descriptions of GLU 2017 and TCDS 2020, reproduced;
* :mod:`~glu.studies.anticipation` — effect anticipation frame by frame (TCDS Fig. 5, notebook 08), which
  notebooks 10 and 12 reuse;
* :mod:`~glu.studies.correspondence` — notebook 10: recognising an action seen from another posture and
  viewpoint, synthetic and real;
* :mod:`~glu.studies.corpus_evaluation` — notebook 11: every fusion strategy on a simulated corpus, a
  factorial design on Dask (``glu evaluate``);
* :mod:`~glu.studies.learning` — notebook 12: learning people's gestures from what their actions did
  (``glu learn-gestures``, ``glu learning-curves``).

Shared by several studies (:data:`SHARED`): :mod:`~glu.studies.anticipation`, and
:mod:`~glu.studies.episodes`, the world of simulated episodes. A study imports the library and the shared
modules, never another study (``tests/harness/test_layout.py``). The runner knows no study by name: it asks
:func:`readme_parts` for the README's results section and :func:`parameter_choices` for the values the
notebooks' parameters may take.
"""

from __future__ import annotations

import importlib
from types import ModuleType

STUDIES: tuple[str, ...] = ("replication", "anticipation", "correspondence", "corpus_evaluation", "learning")
"""The studies, in the order of the story (and of the README's results section)."""
SHARED: tuple[str, ...] = ("anticipation", "episodes")
"""What a study may import of the others."""


def readme_parts() -> list[ModuleType]:
    """Each study's ``readme`` module, in :data:`STUDIES` order: ``TEMPLATE`` (markdown bullets with
    ``{name:format}`` slots), ``REQUIRED`` (the result tables it reads) and ``values(tables)`` (a slot filled
    with a list of sentences is written as bullets under the study's own: :func:`glu.run.readme.values`)."""
    return [importlib.import_module(f"glu.studies.{name}.readme") for name in STUDIES]


def parameter_choices() -> dict[str, tuple[str, ...]]:
    """The values each string parameter of the studies' notebooks may take (each study package's
    ``parameter_choices()``, where it has one), merged; a name means the same thing in every notebook
    (``tests/studies/test_studies.py`` checks that the studies sharing one agree)."""
    out: dict[str, tuple[str, ...]] = {}
    for name in STUDIES:
        study = importlib.import_module(f"glu.studies.{name}")
        out.update(
            {param: tuple(allowed) for param, allowed in getattr(study, "parameter_choices", dict)().items()}
        )
    return out
