"""glu's notebooks, installed with the package as ``glu.notebooks`` so that ``glu reproduce`` runs anywhere.

The notebooks are jupytext percent files (``NN_topic.py``), not modules to import: ``glu reproduce`` and
``glu run`` execute them with papermill. In a source checkout they stay in ``notebooks/`` at the top of the
repository; ``setup.py`` copies this folder into the wheel as ``glu/notebooks/``, so an installed glu carries
them.
"""
