"""Data: the experiment tables, where they come from, downloading them, and synthesising look-alikes."""

from glu.data.source import DataSource, load_experiments, resolve_data
from glu.data.synthetic import WORLD, synthesize_experiments
from glu.data.tables import read_experiments, read_network_definition, write_experiments

__all__ = [
    "WORLD",
    "DataSource",
    "load_experiments",
    "read_experiments",
    "read_network_definition",
    "resolve_data",
    "synthesize_experiments",
    "write_experiments",
]
