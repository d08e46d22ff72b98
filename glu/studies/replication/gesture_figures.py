"""Figures of the gesture chain: segmentation of the recordings, and how well the HMMs recognise actions.

Every function draws on the axes it is given, first argument, and returns them: ``plot_x(ax, frame, …)``;
the ``*_figure`` functions lay out notebooks 01 and 02's figures from them, one call each.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from glu.gestures.segmentation import RecordingSegmentation, Segment, Segmentation
from glu.plots.style import ACTION_COLORS, legend_right, new_figure


def plot_segmentation(
    ax: Axes,
    segmentation: Segmentation | RecordingSegmentation,
    title: str | None = None,
    reference: Sequence[Segment] = (),
) -> Axes:
    """Draw a recording's features (x, y, z), the activity and the segments found on ``ax``.

    Kept segments are shaded and numbered, rejected candidates hatched, tracking events marked in a strip
    below the data (gaps ▼, spikes ·; jumps as dotted lines), reference segments (e.g. the originals)
    drawn as black bars in a strip above it, under the segment numbers. Repaired (interpolated) frames
    are drawn half a frame late.
    Deterministic: the same input gives the same picture.
    """
    pieces = segmentation.pieces if isinstance(segmentation, RecordingSegmentation) else [segmentation]
    colors = {"x": "tab:red", "y": "tab:green", "z": "tab:blue"}
    styles = {"x": "-", "y": "--", "z": ":"}  # told apart without colour too (the activity: dash-dot)
    for k, piece in enumerate(pieces):
        tr = piece.trajectory
        f = tr.frame + np.where(tr.observed, 0.0, 0.5)
        for i, axis in enumerate("xyz"):
            ax.plot(
                f, tr.xyz[:, i], color=colors[axis], ls=styles[axis], lw=0.8, label=axis if k == 0 else None
            )
        ax.plot(f, piece.activity, color="black", ls="-.", lw=1.2, label="activity" if k == 0 else None)
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo - 0.14 * (hi - lo), hi + 0.24 * (hi - lo))  # strips: tracking events below, segments above
    segs = [s for p in pieces for s in p.segments]
    for i, s in enumerate(segs, 1):
        ax.axvspan(s.start, s.end, color="tab:orange", alpha=0.2, lw=0)
        ax.text(
            (s.start + s.end) / 2,
            0.985,
            str(i),
            transform=ax.get_xaxis_transform(),
            ha="center",
            va="top",
            fontsize=9,
        )
    for s, _reason in (r for p in pieces for r in p.rejected):
        ax.axvspan(s.start, s.end, facecolor="none", edgecolor="grey", hatch="//", alpha=0.5, lw=0)
    events = segmentation.events if isinstance(segmentation, RecordingSegmentation) else ()
    xt = ax.get_xaxis_transform()
    gaps = [e.frame - 0.5 for e in events if e.kind == "gap"]
    spikes = [e.frame for e in events if e.kind == "spike"]
    if gaps:
        ax.plot(gaps, [0.05] * len(gaps), ls="none", marker="v", color="purple", transform=xt, label="gap")
    if spikes:
        ax.plot(
            spikes, [0.05] * len(spikes), ls="none", marker=".", color="grey", transform=xt, label="spike"
        )
    for e in events:
        if e.kind == "jump":
            ax.axvline(e.frame - 0.5, color="purple", lw=0.6, ls=":", marker="d", ms=3)  # ends marked
    for s in reference:
        ax.plot([s.start, s.end], [0.87, 0.87], color="black", lw=3, transform=ax.get_xaxis_transform())
    ax.set_xlabel("frame")
    ax.set_ylabel("hand features (body units)\nactivity (0–1)", fontsize=8)
    if title is not None:
        ax.set_title(title)
    handles, _ = ax.get_legend_handles_labels()
    handles += [Patch(color="tab:orange", alpha=0.2, label="segment found")]
    if any(p.rejected for p in pieces):
        handles += [Patch(facecolor="none", edgecolor="grey", hatch="//", label="candidate left out")]
    if reference:
        handles += [Line2D([], [], color="black", lw=3, label="originals' segment")]
    if any(e.kind == "jump" for e in events):
        handles += [Line2D([], [], color="purple", lw=0.6, ls=":", marker="d", ms=3, label="tracking jump")]
    ax.legend(
        handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize="x-small", frameon=False
    )
    return ax


def plot_segmentations(axes: Sequence[Axes], segmentations: Sequence) -> Sequence[Axes]:
    """The automatic segmentation of each recording, one axis each (reference segments as black bars).

    ``segmentations``: (segmentation, reference segments) pairs, as
    :func:`glu.gestures.corpus.recording_segmentations` returns them.
    """
    for ax, (seg, ref) in zip(axes, segmentations, strict=False):
        n = len(seg.segments)
        plot_segmentation(
            ax, seg, title=f"{seg.recording}: {n} segment{'' if n == 1 else 's'}", reference=ref
        )
        ax.title.set_fontsize(9)
    return axes


def segmentation_figure(segmentations: Sequence) -> Figure:
    """Notebook 01's figure: :func:`plot_segmentations` of every recording, one full-width row each, in the
    order given (``segmentations`` as :func:`glu.gestures.corpus.recording_segmentations` returns them)."""
    fig, axes = new_figure(1, width=10, height=2.3, nrows=len(segmentations))
    plot_segmentations(axes, segmentations)
    return fig


def plot_confusion(ax: Axes, confusion: pd.DataFrame) -> Axes:
    """A confusion matrix (rows: true action, columns: predicted), counts in the cells."""
    m = confusion.to_numpy(dtype=float)
    ax.imshow(m, cmap="Blues")
    for i in range(m.shape[0]):
        for j in range(m.shape[1]):
            ax.text(
                j,
                i,
                f"{int(m[i, j])}",
                ha="center",
                va="center",
                color="white" if m[i, j] > m.max() / 2 else "black",
            )
    ax.set_xticks(range(m.shape[1]), confusion.columns)
    ax.set_yticks(range(m.shape[0]), confusion.index)
    ax.set_xlabel("predicted")
    ax.set_ylabel("true")
    return ax


def plot_accuracy_vs_noise(ax: Axes, df: pd.DataFrame) -> Axes:
    """k-fold accuracy against sensor noise, overall (a band: its 95 % Wilson interval) and per action
    (error bars, set a little apart), as :func:`glu.studies.replication.gestures.accuracy_vs_noise` returns
    it."""
    x = df["noise_m"].to_numpy() * 100
    if "ci_low" in df:
        ax.fill_between(x, df["ci_low"], df["ci_high"], color="black", alpha=0.12, lw=0)
    n = int(df["n_sequences"].iloc[0]) if "n_sequences" in df else None
    label = "all actions" if n is None else f"all {n} gestures"
    ax.plot(x, df["accuracy"], "o-", color="black", label=f"{label} (band: 95 % interval)")
    actions = [c.removeprefix("accuracy_") for c in df.columns if c.startswith("accuracy_")]
    step = 0.012 * (x.max() - x.min() if len(x) > 1 else 1.0)
    for k, a in enumerate(actions):
        xa = x + (k - (len(actions) - 1) / 2) * step
        err = None
        if f"ci_low_{a}" in df:
            err = np.vstack(
                [df[f"accuracy_{a}"] - df[f"ci_low_{a}"], df[f"ci_high_{a}"] - df[f"accuracy_{a}"]]
            )
        color = ACTION_COLORS.get(a, "0.5")
        each = "" if n is None else f" ({n // max(len(actions), 1)})"
        ax.errorbar(xa, df[f"accuracy_{a}"], yerr=err, fmt=".--", color=color, elinewidth=0.8, label=a + each)
    ax.set_xlabel("sensor noise (cm, std per joint)")
    ax.set_ylabel("accuracy (95 % Wilson intervals)")
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=8, frameon=False, loc="lower left")
    return ax


def accuracy_figure(confusion: pd.DataFrame, accuracy: float, folds: int, noise: pd.DataFrame) -> Figure:
    """Notebook 02's accuracy on synthetic gestures: the k-fold confusion matrix (:func:`plot_confusion`),
    titled by ``folds`` and the ``accuracy`` it gives, beside the accuracy against sensor noise
    (:func:`plot_accuracy_vs_noise` of ``noise``)."""
    fig, axes = new_figure(2, width=4.2)
    plot_confusion(axes[0], confusion)
    axes[0].set_title(f"{folds}-fold CV, accuracy {accuracy:.3f}", fontsize=9)
    plot_accuracy_vs_noise(axes[1], noise)
    return fig


def plot_segment_scores(ax: Axes, df: pd.DataFrame) -> Axes:
    """Per-frame log-likelihood of each segment under each model (grouped bars), the winner marked."""
    cols = [c for c in df.columns if c.startswith("loglik_")]
    labels = [f"{_wrap(r.recording)}\nframes {r.start}–{r.end}" for r in df.itertuples()]
    w = 0.8 / len(cols)
    per_frame = df[cols].to_numpy() / df["n_frames"].to_numpy()[:, None]
    best = per_frame.argmax(axis=1)
    for k, c in enumerate(cols):
        a = c.removeprefix("loglik_")
        ax.bar(
            np.arange(len(df)) + (k - (len(cols) - 1) / 2) * w,
            per_frame[:, k],
            width=w,
            color=ACTION_COLORS.get(a, "0.5"),
            label=a,
            edgecolor=["black" if b == k else "none" for b in best],
            linewidth=1.5,
        )
    ax.set_xticks(np.arange(len(df)), labels, fontsize=7)
    ax.set_ylabel(r"$(1/T)\,\log L(G \mid A)$")
    ax.set_title("per-frame log-likelihood of each segment (black edge: the recognised action)", fontsize=9)
    handles = [
        Patch(color=ACTION_COLORS.get(c.removeprefix("loglik_"), "0.5"), label=c.removeprefix("loglik_"))
        for c in cols
    ]
    handles.append(Patch(facecolor="white", edgecolor="black", linewidth=1.5, label="recognised"))
    legend_right(ax, handles=handles)
    return ax


def segment_scores_figure(scores: pd.DataFrame) -> Figure:
    """Notebook 02's scores of the test segments under the original models: :func:`plot_segment_scores`
    of ``scores`` (:func:`glu.studies.replication.gestures.original_scores`), 8 inches wide."""
    fig, (ax,) = new_figure(1, width=8)
    plot_segment_scores(ax, scores)
    return fig


def _wrap(name: str, width: int = 16) -> str:
    """A recording name broken at underscores into lines of about ``width`` characters."""
    lines, line = [], ""
    for part in name.split("_"):
        piece = part if not line else f"{line}_{part}"
        if line and len(piece) > width:
            lines.append(line + "_")
            line = part
        else:
            line = piece
    return "\n".join([*lines, line])
