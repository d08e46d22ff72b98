"""Each figure's caption, from the notebook's own prose: the title of its section and the sentence that
interprets it, or the figure's own sentence when its cell draws several.

The site (:mod:`glu.run.site`) shows every figure a notebook saved (the outputs tagged ``{"glu": {"figure":
"NAME.png"}}`` by :meth:`glu.run.outputs.Outputs.figure`) with a caption. The caption is not written twice: it
is read from the executed notebook (:func:`figure_captions`), and put in the metadata of the output that shows
the figure (:func:`caption_figures`), where the site's renderer (:mod:`glu.run.site_render`) finds it. Two
figures of one cell would share their section's prose: each then says what it shows itself
(``out.figure(fig, name, caption=…)``, kept in the output's metadata as ``glu.caption``).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

_HEADING = re.compile(r"^#{1,6}\s+(.*)$")


def _blocks(markdown: str) -> list[tuple[str, str]]:
    """A markdown cell as ("heading", text) and ("text", paragraph) blocks, in order; a heading is one
    line."""
    blocks: list[tuple[str, str]] = []
    lines: list[str] = []

    def flush() -> None:
        if lines:
            blocks.append(("text", " ".join(" ".join(lines).split())))
            lines.clear()

    for line in markdown.splitlines():
        m = _HEADING.match(line.strip())
        if m:
            flush()
            blocks.append(("heading", m.group(1).strip()))
        elif not line.strip():
            flush()
        else:
            lines.append(line.strip())
    flush()
    return blocks


def _sections(source: str) -> tuple[str | None, str | None]:
    """(the last heading of a markdown cell, the first paragraph after it, or of the cell without one)."""
    heading, text = None, None
    for kind, value in _blocks(source):
        if kind == "heading":
            heading, text = value, None
        elif text is None:
            text = value
    return heading, text


def figure_captions(nb: Any) -> dict[int, tuple[str, str]]:
    """Code cell index → the caption of the figures it shows, (title, text), from the notebook's own prose.

    A figure's caption is the heading of its section, then the sentence that interprets it: the first
    paragraph of the markdown cell that follows its cell, when that cell continues the section (it does not
    start with a heading); otherwise the paragraph under the section's heading. (A figure that carries its
    own sentence is captioned with it instead: :func:`caption_figures`.)
    """
    out: dict[int, tuple[str, str]] = {}
    heading, intro = None, None
    cells = nb["cells"]
    for i, cell in enumerate(cells):
        source = "".join(cell.get("source", ""))
        if cell["cell_type"] == "markdown":
            h, t = _sections(source)
            if h is not None:
                heading, intro = h, t
            elif intro is None:
                intro = t
            continue
        if cell["cell_type"] != "code" or not any(_figure_name(o) for o in cell.get("outputs", [])):
            continue
        after = next((c for c in cells[i + 1 :] if c["cell_type"] == "markdown"), None)
        blocks = _blocks("".join(after.get("source", ""))) if after is not None else []
        text = blocks[0][1] if blocks and blocks[0][0] == "text" else intro
        title = re.sub(r"^\d+\s*·\s*", "", heading or "").rstrip(".:")
        out[i] = (title, text or "")
    return out


def _figure_name(output: Mapping[str, Any]) -> str | None:
    return (output.get("metadata") or {}).get("glu", {}).get("figure")


def heading(title: str) -> str:
    """A caption's title in bold, closed by a full stop unless it ends with its own (``?``, ``!``)."""
    return f"**{title}**" if title.endswith(("?", "!", ".")) else f"**{title}.**"


def caption_text(title: str, text: str) -> str:
    """A caption in Markdown: the title in bold, then the text."""
    return f"{heading(title)} {text}" if title and text else (heading(title) if title else text)


def caption_figures(nb: Any) -> dict[str, str]:
    """Put each figure's caption (:func:`figure_captions`) in the metadata of the output that shows it
    (``metadata.glu.title``, ``.text``: the prose that interprets it, and ``.caption``: its own sentence,
    when it has one); returns figure file → caption (:func:`caption_text`: the title, then the figure's own
    sentence, or else the prose)."""
    captions = {}
    for i, (title, text) in figure_captions(nb).items():
        for o in nb["cells"][i].get("outputs", []):
            name = _figure_name(o)
            own = (o.get("metadata") or {}).get("glu", {}).get("caption", "")
            if name and (title or text or own):
                o["metadata"]["glu"].update(title=title, text=text)
                captions[name] = caption_text(title, own or text)
    return captions
