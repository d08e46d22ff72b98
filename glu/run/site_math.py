"""The site's formulas as MathML, written when the site is built: no script, nothing fetched, offline.

Sphinx renders math with MathJax, a script it loads from the web; the site is built and read offline, so
this extension (``html_math_renderer = "mathml"``) converts each formula of the pages (MyST's ``$…$`` and
``$$…$$``, reStructuredText's ``:math:``) from LaTeX to MathML with latex2mathml, which browsers draw
natively. A formula latex2mathml cannot read is a warning, and so fails the build.
"""

from __future__ import annotations

from typing import Any

from docutils import nodes


def mathml(latex: str, display: str = "inline") -> str:
    """A LaTeX formula as a MathML ``<math>`` element (``display``: ``inline`` or ``block``)."""
    from latex2mathml.converter import convert

    return convert(latex.strip(), display=display)


def _converted(translator: Any, node: nodes.Element, display: str) -> str | None:
    from sphinx.util import logging

    try:
        return mathml(node.astext(), display)
    except Exception as e:  # latex2mathml raises its own errors, and others, on what it cannot read
        logging.getLogger(__name__).warning(
            "a formula could not be read (%s): %s", type(e).__name__, node.astext(), location=node
        )
        return None


def visit_inline(translator: Any, node: nodes.Element) -> None:
    """An inline formula: its MathML, or its LaTeX as code when it cannot be read."""
    out = _converted(translator, node, "inline")
    translator.body.append(
        f'<span class="math notranslate">{out}</span>'
        if out is not None
        else f"<code>{translator.encode(node.astext())}</code>"
    )
    raise nodes.SkipNode


def visit_block(translator: Any, node: nodes.Element) -> None:
    """A displayed formula, with its number when it has one."""
    from sphinx.util.math import get_node_equation_number

    out = _converted(translator, node, "block")
    translator.body.append(translator.starttag(node, "div", CLASS="math notranslate"))
    if node.get("number"):
        translator.body.append(f'<span class="eqno">({get_node_equation_number(translator, node)})</span>')
    translator.body.append(out if out is not None else f"<pre>{translator.encode(node.astext())}</pre>")
    translator.body.append("</div>\n")
    raise nodes.SkipNode


def setup(app: Any) -> dict[str, Any]:
    """The Sphinx extension: the ``mathml`` math renderer for HTML."""
    app.add_html_math_renderer("mathml", (visit_inline, None), (visit_block, None))
    return {"parallel_read_safe": True, "parallel_write_safe": True}
