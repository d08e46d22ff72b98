"""Bayesian networks, GLU's or any other: the model, its learning, exact inference (pgmpy-free)."""

from glu.bn.inference import Engine, make_engine
from glu.bn.learning import learn_bn, learn_parameters, learn_structure
from glu.bn.model import BayesNet

__all__ = [
    "BayesNet",
    "Engine",
    "learn_bn",
    "learn_parameters",
    "learn_structure",
    "make_engine",
]
