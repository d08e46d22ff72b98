"""glu: gestures, language and affordances — a reproduction of Saponaro et al. (GLU 2017, TCDS 2020).

The package is organised by the paper's building blocks:

* :mod:`glu.schema`   the variables of the model and their values
* :mod:`glu.data`     loading, validating, fetching and synthesising the data
* :mod:`glu.bn`       the Affordance–Words Bayesian network: learning and exact inference

Heavy libraries (pgmpy, hmmlearn, matplotlib, rerun) are imported only by the modules that need them.
"""

__version__ = "0.1.0"
