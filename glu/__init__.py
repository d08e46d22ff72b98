"""glu: gestures, language and affordances — a reproduction of Saponaro et al. (GLU 2017, TCDS 2020).

The package is built in layers (:data:`LAYERS`), each importing only from those below it:

* the library — the ground (:mod:`glu.errors`, :mod:`glu.paths`, :mod:`glu.files`, :mod:`glu.matfile`,
  :mod:`glu.machine`; above them :mod:`glu.jit`, which finds its cache through :mod:`glu.paths`), the model's
  variables (:mod:`glu.schema`, :mod:`glu.evidence`), the data (:mod:`glu.data`), the gesture HMMs
  (:mod:`glu.hmm`), then side by side the Affordance–Words network (:mod:`glu.bn`), the gesture chain
  (:mod:`glu.gestures`) and the language (:mod:`glu.language`), then fusion (:mod:`glu.fusion`), intervals
  (:mod:`glu.stats`), tidy result frames (:mod:`glu.tidy`), the look of figures (:mod:`glu.plots`), Rerun
  recordings (:mod:`glu.recording`), the saved tables of heavy grids (:mod:`glu.saved`) and the notebooks'
  evidence explorer (:mod:`glu.explorer`);
* the studies (:mod:`glu.studies`), one package per story, above the two they share;
* the notebook runner (:mod:`glu.run`) and the command line (:mod:`glu.cli`).

Heavy libraries (pgmpy, matplotlib, rerun, dask) are imported only by the modules that need them.
"""

__version__ = "0.1.0"

LAYERS: tuple[tuple[str, ...], ...] = (
    ("glu", "glu.errors"),
    ("glu.paths", "glu.files", "glu.matfile", "glu.machine"),
    ("glu.jit",),
    ("glu.schema",),
    ("glu.evidence",),
    ("glu.data",),
    ("glu.hmm",),
    ("glu.bn", "glu.gestures", "glu.language"),
    ("glu.fusion", "glu.stats", "glu.tidy", "glu.plots", "glu.recording", "glu.saved"),
    ("glu.explorer",),
    ("glu.studies.episodes", "glu.studies.anticipation"),
    (
        "glu.studies.replication",
        "glu.studies.correspondence",
        "glu.studies.corpus_evaluation",
        "glu.studies.learning",
    ),
    ("glu.studies",),
    ("glu.run",),
    ("glu.cli",),
    ("glu.__main__",),
)
"""The package's layers, bottom first. A module imports from lower layers and from its own component, never
from a higher layer or a sibling component of its layer (``tests/harness/test_layout.py`` checks every
import): the network, the gestures and the language know nothing of each other, and a study knows no other
study but the shared ones."""
