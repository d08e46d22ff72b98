"""The look of every figure, and the check that a figure can be read.

* :mod:`~glu.plots.style` — colours, sizes, deterministic PNG and SVG (:func:`save_figure`), the
  data-source footer (:func:`stamp`), :func:`new_figure`;
* :mod:`~glu.plots.overlap` — what a reader cannot read in a figure: text on text, a legend on data.

The figures themselves belong to the studies (``glu.studies.<study>.figures``): one plotting function per
figure, one signature, ``plot_x(ax, frame, …) -> Axes``, drawing a tidy frame on the axes it is given.
"""

from glu.plots.style import ACTION_COLORS, VALUE_COLORS, new_figure, save_figure, stamp

__all__ = ["ACTION_COLORS", "VALUE_COLORS", "new_figure", "save_figure", "stamp"]
