"""Bayesian networks, GLU's or any other: the model, its learning, exact inference (pgmpy-free)."""

from glu.bn.core import CoreEngine
from glu.bn.inference import InferenceEngine
from glu.bn.junction import JunctionTreeEngine
from glu.bn.learning import learn_bn, learn_parameters, learn_structure
from glu.bn.model import BayesNet

__all__ = [
    "BayesNet",
    "CoreEngine",
    "InferenceEngine",
    "JunctionTreeEngine",
    "learn_bn",
    "learn_parameters",
    "learn_structure",
]
