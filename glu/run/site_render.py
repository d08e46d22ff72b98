"""MyST-NB's renderer for glu's notebooks: each figure a glu notebook saved is shown with its caption.

:func:`glu.run.captions.caption_figures` puts each figure's caption into the metadata of the output that
shows it (``{"glu": {"figure": "NAME.png", "title": "…", "text": "…", "caption": "…"}}``); this renderer
(MyST-NB's ``nb_render_plugin = "glu"``, an entry point of the group ``myst_nb.renderers``) wraps that image
in a figure with the caption, its Markdown rendered inline, and the file's name on a line of its own
(``glu-file``). Any other output is rendered as MyST-NB renders it.
"""

from __future__ import annotations

import dataclasses

from docutils import nodes
from myst_nb.core.render import MimeData, NbElementRenderer

from glu.run.captions import heading


class FigureRenderer(NbElementRenderer):
    """MyST-NB's default renderer, with a caption under every figure of glu's (see the module docstring)."""

    def _inline(self, data: MimeData, markdown: str) -> list[nodes.Node]:
        return self.render_markdown_inline(
            dataclasses.replace(data, mime_type="text/markdown", content=markdown, output_metadata={})
        )

    def render_image(self, data: MimeData) -> list[nodes.Element]:
        """The image, inside a figure with its caption when the output carries one.

        The caption shows the section's title, the figure's own sentence when it has one, and the file; the
        prose that interprets the figure, which the page shows right after it anyway, is the figure's
        legend, shown when the figure is opened."""
        images = super().render_image(data)
        meta = data.output_metadata.get("glu") or {}
        title, text, name = meta.get("title", ""), meta.get("text", ""), meta.get("figure", "")
        own = meta.get("caption", "")
        if not (title or text or own) or len(images) != 1:
            return images
        image = images[0]
        image["alt"] = name or "figure"
        figure = nodes.figure("", image, classes=["glu-figure"])
        head = " ".join(p for p in (heading(title) if title else "", own) if p)
        file = nodes.inline("", "", nodes.literal(name, name), classes=["glu-file"])
        figure += nodes.caption("", "", *(self._inline(data, head) if head else []), file)
        if text:
            figure += nodes.legend(
                "", nodes.paragraph("", "", *self._inline(data, text)), classes=["glu-interpretation"]
            )
        return [figure]
