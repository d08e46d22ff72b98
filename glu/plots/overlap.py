"""Find what a reader cannot read in a figure: text on text, a legend on data, a label on a line.

:func:`figure_problems` draws a figure (Agg) and returns one line per problem, empty when there is none:

* **text on text**: two drawn text elements (tick labels, axis labels, titles, legend entries, value
  labels, annotations, the footer) whose boxes overlap, or that stand side by side on one line with less
  than :data:`WORD_GAP_PX` between them (they read as one);
* **text on another panel**: a text element (or a legend) of one axes inside another axes;
* **legend on data**: a legend whose entries, or its frame when it has one, cover a line, a marker, a
  bar, a band, an error bar or an image of any axes;
* **label on data**: a text placed in an axes (a value label, an annotation) that covers a line, a
  marker, an error bar or the edge of an opaque bar of that axes (text inside a bar, on an image — the
  cells of a heat map — or on translucent shading is meant to be read there);
* **label across the frame**: such a text that crosses the axes' frame, or that is placed at a data point
  but drawn outside the axes (a value label run past the frame);
* **colour alone**: more than :data:`MAX_BY_COLOUR` series in one axes, two of which differ by colour only
  (the same marker, line style and hatch): a reader who does not see colours well cannot tell them apart.
  A series is a line, a set of bars or error bars, or a scatter, with what it draws in the same colour.

Only what is drawn counts (the texts the renderer is asked to draw; lines, bars and bands clipped to their
axes). Boxes touching by less than :data:`TOLERANCE_PX` are not an overlap. With the environment variable
:data:`CHECK_ENV` naming a folder, :func:`glu.plots.style.save_figure` writes each figure's problems
there (``<name>.txt``, empty when there are none); the test suite reads them after running the notebooks.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.collections import Collection, PathCollection
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from matplotlib.lines import Line2D
from matplotlib.markers import MarkerStyle
from matplotlib.patches import Patch
from matplotlib.text import Text
from matplotlib.transforms import Bbox

CHECK_ENV = "GLU_FIGURE_CHECK"
"""Environment variable: a folder where :func:`glu.plots.style.save_figure` writes each figure's problems."""
WORD_GAP_PX = 2.0
"""Upright texts side by side on one line need at least this gap (pixels), or they read as one."""
TOLERANCE_PX = 1.0
"""Boxes must overlap by more than this (pixels at the figure's dpi, in both directions) to count."""
BACKGROUND_ALPHA = 0.35
"""Shading at most this opaque (bands, spans) is a background a label may sit on; a legend may not."""
MAX_BY_COLOUR = 4
"""Up to this many series in one axes may be told apart by colour alone; beyond it each needs its own marker,
line style or hatch (colour-blind readers, greyscale prints)."""
_NO_STYLE = ("None", "none", "", " ")
"""The line styles (and markers, with None) that draw nothing."""


@dataclass(frozen=True)
class _Drawn:
    """A drawn text element: its corners and enclosing box in display pixels, its name, its axes.

    ``corners``, shape (4, 2): the text's own rectangle, turned with the text (a rotated tick label is a
    rotated rectangle, not the larger upright box around it).
    """

    corners: np.ndarray
    box: Bbox
    name: str
    axes: Axes | None
    artist: Artist
    upright: bool = True


def figure_problems(fig: Figure, dpi: float = 150.0) -> list[str]:
    """Render ``fig`` as it is saved; one line per readability problem (module docstring), [] if none.

    The figure is rendered as :func:`glu.plots.style.save_figure` saves it (PNG at ``dpi``, cropped with
    ``bbox_inches="tight"``, which moves whatever is placed relative to the figure's edges), and checked
    as drawn. Drawing a figure can move what a layout engine places, so :func:`glu.plots.style.save_figure`
    checks the very drawing it saves (:func:`watching`) rather than calling this first.
    """
    with watching(fig) as problems:
        fig.savefig(io.BytesIO(), format="png", dpi=dpi, bbox_inches="tight")
    return problems


@contextmanager
def watching(fig: Figure) -> Iterator[list[str]]:
    """Check ``fig`` each time it is drawn in the block (by a ``savefig``); the yielded list then holds the
    problems found in the last drawing. Nothing drawn is changed."""
    problems: list[str] = []
    drawn: list[Text] = []
    draw = fig.draw

    def checked_draw(renderer) -> None:
        drawn.clear()
        draw(renderer)
        problems[:] = _problems(fig, renderer, drawn)

    fig.draw = checked_draw
    try:
        with _recording_texts(drawn):
            yield problems
    finally:
        del fig.draw


def _problems(fig: Figure, renderer, drawn_texts: list[Text]) -> list[str]:
    texts = [t for t in (_drawn(t, renderer) for t in dict.fromkeys(drawn_texts)) if t is not None]
    legends = [lg for lg in _legends(fig) if lg.get_visible()]
    problems: list[str] = []
    legend_boxes = {id(lg): _legend_box(lg, renderer) for lg in legends}
    in_legend = {id(t): lg for lg in legends for t in [*lg.get_texts(), lg.get_title()]}
    for i, a in enumerate(texts):
        for b in texts[i + 1 :]:
            if (_overlap(a.box, b.box) and _polygons_overlap(a.corners, b.corners)) or _side_by_side(a, b):
                problems.append(f"text on text: {a.name} and {b.name}")
        for lg in legends:
            box = legend_boxes[id(lg)]
            if in_legend.get(id(a.artist)) is not lg and _polygons_overlap(a.corners, _corners(box)):
                problems.append(f"text on text: {a.name} and the legend {_legend_name(lg)}")
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
    for t in texts:
        for ax in axes:
            if ax is t.axes or id(t.artist) in in_legend:
                continue
            if _polygons_overlap(t.corners, _corners(ax.bbox)):
                problems.append(f"text on another panel: {t.name} inside {_axes_name(ax)}")
    for lg in legends:
        box = legend_boxes[id(lg)]
        for ax in axes:
            if ax is not lg.axes and _overlap(box, ax.bbox):
                problems.append(
                    f"text on another panel: the legend {_legend_name(lg)} inside {_axes_name(ax)}"
                )
            for artist, what in _data(ax, renderer, background=True):
                if _covers(artist, box, ax, renderer):
                    problems.append(f"legend on data: the legend {_legend_name(lg)} covers {what}")
                    break
    for t in texts:
        if t.axes is None or not _placed_in_axes(t.artist):
            continue
        ax = t.axes
        inner = ax.bbox.padded(-TOLERANCE_PX)
        if not _inside(t.box, ax.bbox.padded(TOLERANCE_PX)):
            if _overlap(t.box, ax.bbox):
                problems.append(f"label across the frame: {t.name} crosses the frame of {_axes_name(ax)}")
            elif _anchored_in_data(t.artist):
                problems.append(
                    f"label across the frame: {t.name}, placed at a data point, is outside {_axes_name(ax)}"
                )
        on = Bbox.intersection(t.box, inner)
        for artist, what in _data(ax, renderer, background=False) if on is not None else ():
            if _covers(artist, on, ax, renderer, inside_ok=True):
                problems.append(f"label on data: {t.name} covers {what}")
                break
    problems += [p for ax in axes for p in colour_alone(ax)]
    return list(dict.fromkeys(problems))


# ---------------------------------------------------------------- series told apart by colour only
def _line_signature(line: Line2D) -> tuple[str, str]:
    drawn_marker = _has_marker(line) and line.get_markersize() > 0
    return (
        str(line.get_marker()) if drawn_marker else "",
        str(line.get_linestyle()) if _has_line(line) else "",
    )


def _has_marker(line: Line2D) -> bool:
    return line.get_marker() not in (None, *_NO_STYLE)


def _has_line(line: Line2D) -> bool:
    return line.get_linestyle() not in _NO_STYLE and line.get_linewidth() > 0


def _series(ax: Axes) -> list[tuple[str, str, tuple]]:
    """The series of ``ax``: (colour, label, signature: what tells it apart besides its colour)."""
    from matplotlib.colors import to_hex

    out: list[tuple[str, str, tuple]] = []
    taken: set[int] = set()
    for c in ax.containers:  # bars and error bars: the container is the series
        label = str(c.get_label() or "")
        if hasattr(c, "patches"):
            patches = [p for p in c.patches if p.get_visible()]
            taken.update(id(p) for p in c.patches)
            if patches:
                sig = ("bars", patches[0].get_hatch() or "", str(patches[0].get_linestyle()))
                out.append((to_hex(patches[0].get_facecolor()), label, sig))
        elif hasattr(c, "lines"):
            data_line, caps, bars = c.lines
            taken.update(id(x) for x in [data_line, *caps, *bars] if x is not None)
            if data_line is not None and data_line.get_visible():
                out.append((to_hex(data_line.get_color()), label, ("line", *_line_signature(data_line))))
    for line in ax.lines:
        if id(line) in taken or not line.get_visible() or not len(line.get_xydata()):
            continue
        sig = _line_signature(line)
        if any(sig):
            out.append((to_hex(line.get_color()), str(line.get_label() or ""), ("line", *sig)))
    for coll in ax.collections:
        if isinstance(coll, PathCollection) and coll.get_visible() and len(coll.get_offsets()):
            faces = coll.get_facecolors() if len(coll.get_facecolors()) else coll.get_edgecolors()
            paths = coll.get_paths()
            shape = tuple(np.round(paths[0].vertices, 2).ravel()) if paths else ()
            if len(faces):
                out.append((to_hex(faces[0]), str(coll.get_label() or ""), ("points", shape)))
    return out


def colour_alone(ax: Axes) -> list[str]:
    """The "colour alone" problems of one axes (module docstring): series, grouped by colour (a line and
    the markers or bars of one colour are one series), of which two draw alike but for their colour."""
    groups: dict[str, tuple[str, set[tuple]]] = {}
    for colour, label, sig in _series(ax):
        name, sigs = groups.get(colour, ("", set()))
        groups[colour] = (name or ("" if label.startswith("_") else label), sigs | {sig})
    if len(groups) <= MAX_BY_COLOUR:
        return []
    by_look: dict[frozenset, list[str]] = {}
    for colour, (name, sigs) in groups.items():
        by_look.setdefault(frozenset(sigs), []).append(repr(_short(name, 24)) if name else colour)
    alike = [names for names in by_look.values() if len(names) > 1]
    return [
        f"colour alone: {len(groups)} series in {_axes_name(ax)}, and {', '.join(names)} differ only by "
        "colour (give each a marker, line style or hatch of its own)"
        for names in alike
    ]


# ---------------------------------------------------------------- what is drawn
@contextmanager
def _recording_texts(drawn: list[Text]) -> Iterator[list[Text]]:
    """Append to ``drawn`` every Text drawn meanwhile (at :meth:`Text.draw`, so that multi-line texts count:
    the renderer's ``draw_text`` receives those line by line, without the Text they belong to)."""
    original = Text.draw

    def draw(self, renderer):
        if self.get_visible() and self.get_text().strip():
            drawn.append(self)
        return original(self, renderer)

    Text.draw = draw
    try:
        yield drawn
    finally:
        Text.draw = original


def _drawn(t: Text, renderer) -> _Drawn | None:
    box = t.get_window_extent(renderer)  # a visible, non-blank text (as recorded)
    if box.width <= 0 or box.height <= 0:  # e.g. a zero-width space
        return None
    angle = t.get_rotation() % 180
    if min(angle, 180 - angle, abs(angle - 90)) < 1e-6:
        corners = _corners(box)
    else:  # the text's own rectangle: its size upright, turned about the centre of the upright box around it
        rotation = t.get_rotation()
        t.set_rotation(0)
        upright = t.get_window_extent(renderer)
        t.set_rotation(rotation)
        w, h = upright.width / 2, upright.height / 2
        a = np.deg2rad(rotation)
        turn = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        local = np.array([[-w, -h], [w, -h], [w, h], [-w, h]])
        corners = local @ turn.T + [(box.x0 + box.x1) / 2, (box.y0 + box.y1) / 2]
    level = abs(angle) < 1e-6 or abs(angle - 180) < 1e-6
    return _Drawn(corners, box, repr(_short(t.get_text())), t.axes, t, upright=level)


def _corners(box: Bbox) -> np.ndarray:
    return np.array([[box.x0, box.y0], [box.x1, box.y0], [box.x1, box.y1], [box.x0, box.y1]])


def _polygons_overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two convex polygons (corners in order, shape (n, 2)) overlap by more than the tolerance.

    Separating axes: they overlap unless, along the normal of some edge, their projections are apart or
    overlap by at most :data:`TOLERANCE_PX`.
    """
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        for ex, ey in edges:
            n = np.hypot(ex, ey)
            if n == 0:
                continue
            axis = np.array([-ey, ex]) / n
            pa, pb = a @ axis, b @ axis
            if min(pa.max(), pb.max()) - max(pa.min(), pb.min()) <= TOLERANCE_PX:
                return False
    return True


def _side_by_side(a: _Drawn, b: _Drawn) -> bool:
    """Two upright texts on one line closer than :data:`WORD_GAP_PX`: they read as one ("mediumObjVel")."""
    if not (a.upright and b.upright):
        return False  # a rotated text: its rectangle is checked as such
    same_line = min(a.box.y1, b.box.y1) - max(a.box.y0, b.box.y0) > TOLERANCE_PX
    gap = max(a.box.x0, b.box.x0) - min(a.box.x1, b.box.x1)
    return same_line and gap < WORD_GAP_PX


def _legends(fig: Figure) -> list[Legend]:
    return [*fig.legends, *(lg for ax in fig.axes if (lg := ax.get_legend()) is not None)]


def _legend_box(lg: Legend, renderer) -> Bbox:
    """The legend's frame when it draws one, else the box of its entries and title."""
    return (lg if lg.get_frame_on() else lg._legend_box).get_window_extent(renderer)


def _placed_in_axes(t: Text) -> bool:
    """A text the author placed among the data (ax.text, annotate, bar_label), not a tick label or title."""
    return t.axes is not None and t in t.axes.texts


def _anchored_in_data(t: Text) -> bool:
    """Whether ``t`` is placed at a data point (ax.text in data coordinates, annotate/bar_label at one)."""
    from matplotlib.text import Annotation

    if isinstance(t, Annotation):
        return t.xycoords == "data"
    return t.get_transform() == t.axes.transData


def _data(ax: Axes, renderer, background: bool) -> Iterator[tuple[Artist, str]]:
    """The drawn data artists of ``ax`` and a name for each; ``background``: include translucent shading."""
    for line in ax.lines:
        if line.get_visible() and len(line.get_xydata()):
            yield line, f"the line {_label(line)} of {_axes_name(ax)}"
    for p in ax.patches:
        if p.get_visible() and _is_drawn_patch(p) and (background or _opaque(p)):
            yield p, f"the bar/patch {_label(p)} of {_axes_name(ax)}"
    for c in ax.collections:
        if c.get_visible() and (background or _opaque(c)):
            yield c, f"the {type(c).__name__} {_label(c)} of {_axes_name(ax)}"
    if background:
        for im in ax.images:
            if im.get_visible():
                yield im, f"the image of {_axes_name(ax)}"


def _is_drawn_patch(p: Patch) -> bool:
    face = p.get_facecolor()
    fill = p.get_fill() and face[3] > 0
    edge = p.get_linewidth() > 0 and p.get_edgecolor()[3] > 0
    return bool(fill or edge or p.get_hatch())


def _opaque(artist: Artist) -> bool:
    if isinstance(artist, Patch):
        a = max(artist.get_facecolor()[3] if artist.get_fill() else 0.0, artist.get_edgecolor()[3])
    else:  # a Collection: _data asks about nothing else
        a = max([c[3] for c in artist.get_facecolors()] + [c[3] for c in artist.get_edgecolors()] + [0.0])
    alpha = artist.get_alpha()
    return (alpha if alpha is not None else 1.0) * a > BACKGROUND_ALPHA


def _covers(artist: Artist, box: Bbox, ax: Axes, renderer, inside_ok: bool = False) -> bool:
    """Whether ``artist`` (clipped to its axes) draws anything inside ``box`` (display pixels).

    ``inside_ok``: a box wholly inside a bar or patch does not count, only one across its edge (a value
    label written inside its bar is readable; one across the bar's edge is not).
    """
    area = Bbox.intersection(box, ax.bbox) if artist.get_clip_on() else box
    if area is None or area.width <= TOLERANCE_PX or area.height <= TOLERANCE_PX:
        return False
    area = area.padded(-TOLERANCE_PX / 2)
    if isinstance(artist, Line2D):
        path = artist.get_transform().transform_path(artist.get_path())
        if _has_line(artist) and len(path.vertices) > 1 and path.intersects_bbox(area, filled=False):
            return True
        return _has_marker(artist) and _points_in(path.vertices, _marker_reach(artist, area, renderer))
    if isinstance(artist, Patch):
        path = artist.get_transform().transform_path(artist.get_path())
        ext = path.get_extents()
        if ext.width < 0.5 and ext.height < 0.5:
            return False
        return path.intersects_bbox(area, filled=bool(artist.get_fill()) and not inside_ok)
    if isinstance(artist, PathCollection):  # scatter: markers at the offsets
        offsets = artist.get_offset_transform().transform(artist.get_offsets())
        sizes = artist.get_sizes()
        r = np.sqrt(sizes.max() if len(sizes) else 0.0) * renderer.points_to_pixels(1.0) / 2
        return _points_in(offsets, area.padded(r))
    if isinstance(artist, Collection):
        t = artist.get_transform()
        filled = len(artist.get_facecolors()) > 0 and artist.get_facecolors()[:, 3].max() > 0
        return any(t.transform_path(p).intersects_bbox(area, filled=filled) for p in artist.get_paths())
    return _overlap(artist.get_window_extent(renderer), area)  # an AxesImage: _data yields nothing else


def _marker_reach(line: Line2D, box: Bbox, renderer) -> Bbox:
    """``box`` grown by the extent of the line's marker: a marker centre inside it draws inside ``box``."""
    style = MarkerStyle(line.get_marker())
    ext = style.get_transform().transform_path(style.get_path()).get_extents()
    px = renderer.points_to_pixels(1.0)
    edge = line.get_markeredgewidth() * px / 2
    size = line.get_markersize() * px
    return Bbox.from_extents(
        box.x0 - ext.x1 * size - edge,
        box.y0 - ext.y1 * size - edge,
        box.x1 - ext.x0 * size + edge,
        box.y1 - ext.y0 * size + edge,
    )


def _points_in(points: np.ndarray, box: Bbox) -> bool:
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    p = p[np.isfinite(p).all(axis=1)]
    inside = (p[:, 0] >= box.x0) & (p[:, 0] <= box.x1) & (p[:, 1] >= box.y0) & (p[:, 1] <= box.y1)
    return bool(inside.any())


def _overlap(a: Bbox, b: Bbox) -> bool:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return w > TOLERANCE_PX and h > TOLERANCE_PX


def _inside(a: Bbox, b: Bbox) -> bool:
    return a.x0 >= b.x0 and a.x1 <= b.x1 and a.y0 >= b.y0 and a.y1 <= b.y1


# ---------------------------------------------------------------- names in the messages
def _axes_name(ax: Axes) -> str:
    fig = ax.figure
    k = fig.axes.index(ax) + 1 if fig is not None and ax in fig.axes else 0
    title = ax.get_title() or ax.get_ylabel() or ax.get_xlabel()
    return f"panel {k}" + (f" ({_short(title)})" if title else "")


def _legend_name(lg: Legend) -> str:
    labels = [t.get_text() for t in lg.get_texts()]
    return "[" + ", ".join(_short(x, 20) for x in labels[:3]) + (", …]" if len(labels) > 3 else "]")


def _label(artist: Artist) -> str:
    label = str(artist.get_label() or "")
    return "" if label.startswith("_") else repr(_short(label, 30))


def _short(s: str, n: int = 40) -> str:
    s = " ".join(str(s).split())
    return s if len(s) <= n else s[: n - 1] + "…"
