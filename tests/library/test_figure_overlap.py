"""The readability check of figures (glu.plots.overlap): it catches what it should; no figure fails it.

The first tests build figures with a known fault by hand (two labels on each other, a legend on bars, a
value label past the frame, …) and the same figures without it: the checker must name the fault and
pass the clean version. The last tests read the checker's verdict on every figure the notebooks write:
the quick run of the notebook tests (synthetic data) has ``GLU_FIGURE_CHECK`` set, and with the real data
the notebooks whose figures exist only there (the original HMMs, the seated taps) run quickly here.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from glu.plots.overlap import CHECK_ENV, figure_problems  # noqa: E402


@pytest.fixture
def fig():
    f, ax = plt.subplots(figsize=(4, 3))
    yield f, ax
    plt.close(f)


def test_two_tick_labels_on_each_other_are_caught(fig):
    f, ax = fig
    ax.set_xticks([0, 0.02], ["a long tick label", "another long one"])
    problems = figure_problems(f)
    assert any("text on text" in p and "a long tick label" in p for p in problems), problems


def test_multi_line_texts_on_each_other_are_caught(fig):
    """Texts of several lines count too (matplotlib draws them line by line, without their Text)."""
    f, ax = fig
    f.text(0.3, 0.5, "a first text\nof two lines")
    f.text(0.32, 0.47, "a second\nalso of two")
    problems = figure_problems(f)
    assert any("text on text" in p and "a first text" in p for p in problems), problems


def test_tick_labels_apart_pass(fig):
    f, ax = fig
    ax.set_xticks([0, 1], ["a label", "another"])
    ax.set_xlim(-0.5, 1.5)
    assert figure_problems(f) == []


def test_rotated_labels_are_rotated_rectangles(fig):
    """Two 45° labels side by side: their upright boxes overlap, the labels themselves do not."""
    f, ax = fig
    ax.set_xticks([0, 1], ["rotated label one", "rotated label two"], rotation=45, ha="right")
    ax.set_xlim(-0.5, 1.5)
    assert figure_problems(f) == []
    ax.set_xlim(-20, 20)  # now they touch along their length
    problems = figure_problems(f)
    assert any("rotated label one" in p and "rotated label two" in p for p in problems), problems


def test_a_legend_on_bars_is_caught_and_one_beside_them_passes(fig):
    f, ax = fig
    ax.bar([0, 1, 2], [0.95, 0.5, 0.3], label="bars")
    ax.set_ylim(0, 1)
    ax.legend(loc="upper left")
    problems = figure_problems(f)
    assert any(p.startswith("legend on data") and "bar" in p for p in problems), problems
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1))
    assert figure_problems(f) == []


def test_a_legend_on_a_line_or_a_band_is_caught(fig):
    f, ax = fig
    x = np.linspace(0, 1, 50)
    ax.fill_between(x, 0.8, 0.95, alpha=0.12, label="band")
    ax.plot(x, 0.1 + 0 * x, label="line")
    ax.legend(loc="upper right", frameon=False)
    problems = figure_problems(f)
    assert any("legend on data" in p and "PolyCollection" in p for p in problems), problems
    ax.set_ylim(0, 1.6)  # room above the band: the legend sits on nothing
    assert figure_problems(f) == []


def test_a_legend_on_markers_is_caught(fig):
    f, ax = fig
    ax.plot([0.05, 0.5], [0.95, 0.5], "o", ls="none", label="points")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.legend(loc="upper left")
    assert any("legend on data" in p and "'points'" in p for p in figure_problems(f))


def test_a_value_label_on_a_line_and_past_the_frame_is_caught(fig):
    f, ax = fig
    ax.barh([0, 1], [0.3, 0.97])
    ax.axvline(0.33, ls=":", label="uniform")
    ax.set_xlim(0, 1)
    ax.text(0.31, 0, "0.300", va="center")  # on the dotted line
    ax.text(0.98, 1, "0.970", va="center")  # runs past the right frame
    ax.text(1.05, 0, "1.050", va="center")  # placed at a data point outside the axes
    problems = figure_problems(f)
    assert any("label on data: '0.300'" in p and "uniform" in p for p in problems), problems
    assert any("'0.970' crosses the frame" in p for p in problems), problems
    assert any("'1.050', placed at a data point, is outside" in p for p in problems), problems


def test_value_labels_on_a_heat_map_and_on_shading_pass(fig):
    f, ax = fig
    ax.imshow(np.arange(4).reshape(2, 2))
    for i in range(2):
        for j in range(2):
            ax.text(j, i, f"{i + j}", ha="center", va="center")
    ax.axvspan(-0.5, 0.5, alpha=0.2)
    assert figure_problems(f) == []


def test_a_tick_label_reaching_into_the_next_panel_is_caught():
    f, (a, b) = plt.subplots(1, 2, figsize=(6, 3))
    b.set_yticks([0.5], ["a y tick label long enough to reach the panel on its left"])
    problems = figure_problems(f)
    plt.close(f)
    assert any("text on another panel: 'a y tick label" in p and "panel 1" in p for p in problems), problems


def test_the_footer_on_the_x_label_is_caught(fig):
    f, ax = fig
    ax.set_xlabel("an x label")
    f.tight_layout()
    f.canvas.draw()
    box = ax.xaxis.label.get_window_extent(f.canvas.get_renderer())
    x, y = f.transFigure.inverted().transform(((box.x0 + box.x1) / 2, (box.y0 + box.y1) / 2))
    f.text(x, y, "data: somewhere", ha="center", va="center")
    problems = figure_problems(f)
    assert any("text on text" in p and "'an x label'" in p and "'data: somewhere'" in p for p in problems)


def test_the_check_is_written_beside_the_figures_when_asked(tmp_path, monkeypatch, fig):
    from glu.plots.style import save_figure

    f, ax = fig
    ax.set_xticks([0, 0.01], ["one label", "two labels"])
    monkeypatch.setenv(CHECK_ENV, str(tmp_path / "check"))
    save_figure(f, tmp_path / "figures" / "crowded")
    report = (tmp_path / "check" / "crowded.txt").read_text()
    assert "text on text: 'one label' and 'two labels'" in report


def test_a_relative_check_folder_is_refused_and_nothing_is_written(tmp_path, monkeypatch, fig):
    """A relative folder would be taken in each kernel's working folder (GLU_FIGURE_CHECK=1 once left
    reports in notebooks/1/)."""
    from glu.plots.style import save_figure

    f, _ = fig
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv(CHECK_ENV, "1")
    with pytest.raises(ValueError, match=r"GLU_FIGURE_CHECK .* absolute path, not '1'"):
        save_figure(f, tmp_path / "figures" / "plain")
    assert list(tmp_path.iterdir()) == []


def test_a_value_label_inside_its_bar_passes_and_one_across_its_edge_is_caught(fig):
    f, ax = fig
    ax.bar([0, 1], [0.8, 0.05], width=0.6)
    ax.set_ylim(0, 1)
    ax.text(0, 0.4, "0.80", ha="center", va="center")  # inside the bar
    assert figure_problems(f) == []
    ax.text(1, 0.05, "0.05", ha="center", va="center")  # across the top of the short bar
    assert any("label on data: '0.05'" in p for p in figure_problems(f))


def test_the_figure_is_checked_as_saved_tightly_cropped(fig):
    """A legend at the figure's bottom edge moves, in the cropped file, onto a footer written below it."""
    from glu.plots.style import stamp

    f, ax = fig
    ax.plot([0, 1], [0, 1], label="a line")
    f.legend(loc="lower center", ncols=1)
    f.subplots_adjust(bottom=0.3)
    assert figure_problems(f) == []
    stamp(f, "the data this figure was drawn from")
    problems = figure_problems(f)
    assert any("the data this figure" in p and "legend" in p for p in problems), problems


@pytest.mark.parametrize("words", [3, 40, 120])
@pytest.mark.parametrize("size", [(3.0, 2.0), (6.0, 3.0), (12.0, 5.0)])
def test_the_made_by_line_lies_below_the_footer_whatever_its_lines(fig, words, size):
    """The "glu …, commit …" line sits wholly below the footer, however many lines the footer wraps into
    (measured by matplotlib's own text extents, multi-line text included)."""
    from glu.plots.style import stamp

    f, ax = fig
    f.set_size_inches(*size)
    ax.plot([0, 1], [0, 1])
    stamp(f, " ".join(["parameter=value"] * words), "glu 0.1.0, commit 0123456789ab")
    r = f.canvas.get_renderer()
    footer, made_by = (t.get_window_extent(r) for t in f.texts[-2:])
    assert made_by.y1 < footer.y0 and made_by.x0 == pytest.approx(footer.x0)


def _anticipation_frames(case: str = "sphere", n: int = 40):
    """Made-up frames shaped like AnticipationRun.curves(), .predictions() and published_comparison()."""
    import pandas as pd

    t = np.arange(1, n + 1)
    frames = 120 + t
    rows = []
    for k, action in enumerate(("grasp", "tap", "touch")):
        ll = -0.05 * (k + 1) * t + np.sin(t / 5 + k)
        p = np.full(n, [0.2, 0.6, 0.2][k])
        rows += [
            {"case": case, "models": "made-up", "frame": f, "t": i, "seconds": (i - 1) / 30, "action": action}
            | {"loglik_per_frame": v, "p_hmm": q}
            for f, i, v, q in zip(frames, t, ll, p, strict=True)
        ]
    curves = pd.DataFrame(rows)
    updates = t[4::5]
    preds = pd.DataFrame(
        [
            {"case": case, "frame": 120 + u, "t": u, "node": "ObjVel", "value": v, "p": p}
            for u in updates
            for v, p in zip(("slow", "medium", "fast"), (0.05, 0.43, 0.52), strict=True)
        ]
    )
    pub = [
        ("loglik_per_frame", r.action, r.t, r.loglik_per_frame, r.loglik_per_frame + 1e-5, 3e-5)
        for r in curves.itertuples()
    ]
    pub += [
        ("ObjVel", v, updates[-1], p, p + 1e-6, 6e-6)
        for v, p in (("slow", 0.05), ("medium", 0.43), ("fast", 0.52))
    ]
    published = pd.DataFrame(pub, columns=["quantity", "key", "t", "ours", "paper", "resolution"])
    published["difference"] = published["ours"] - published["paper"]
    return curves, preds, published


def test_the_check_changes_no_saved_file_and_passes_the_hero_figure(tmp_path, monkeypatch):
    """The hero's layout (constrained, a legend above, a seconds axis on top) moves when drawn twice: the
    check must watch the drawing that is saved, not draw first."""
    from glu.plots.style import save_figure, stamp
    from glu.studies.anticipation.figures import anticipation_figure

    curves, preds, published = _anticipation_frames()
    written = {}
    for name, check in (("plain", None), ("checked", tmp_path / "check")):
        if check is not None:
            monkeypatch.setenv(CHECK_ENV, str(check))
        f = anticipation_figure([(curves, preds), (curves.assign(case="box"), preds)], [published, None])
        stamp(f, "made-up data")
        written[name] = [p.read_bytes() for p in save_figure(f, tmp_path / name / "hero")]
        plt.close(f)
    assert written["plain"] == written["checked"]
    assert (tmp_path / "check" / "hero.txt").read_text() == ""


REAL_DATA_NOTEBOOKS = ["02", "08", "10"]
"""The notebooks with figures only the real data has: the original HMMs' scores, the hero (TCDS Fig. 5
against the paper), the nested cross-validation on the standing segments. The other notebooks' figures are
checked in the quick run of tests/harness/test_notebooks.py."""


def _checked_run(data, out, check, monkeypatch, **kwargs) -> list[str]:
    """Run notebooks with the check on; the problems of every figure written, as "name: problem" lines."""
    from glu.run.reproduce import reproduce

    monkeypatch.setenv(CHECK_ENV, str(check))
    summary = reproduce(data=data, out=out, jobs=2, log=lambda _: None, site=False, **kwargs)
    assert all(n["status"] == "ok" for n in summary["notebooks"])
    pngs = sorted((out / "figures").glob("*.png"))
    assert pngs and all((check / f"{p.stem}.txt").is_file() for p in pngs)
    return [f"{p.stem}: {line}" for p in pngs for line in (check / f"{p.stem}.txt").read_text().splitlines()]


@pytest.mark.shared_data
def test_the_figures_only_the_real_data_has_pass_the_check(shared_data, tmp_path, monkeypatch):
    out, check = tmp_path / "out", tmp_path / "check"
    problems = _checked_run(shared_data, out, check, monkeypatch, quick=True, only=REAL_DATA_NOTEBOOKS)
    names = {p.stem for p in (out / "figures").glob("*.png")}
    assert {"hmm_original_scores", "tcds_anticipation_original", "correspondence_nested_cv"} <= names
    assert not problems, "\n".join(problems)


@pytest.mark.slow
@pytest.mark.shared_data
def test_every_figure_of_the_full_run_on_the_real_data_passes_the_check(shared_data, tmp_path, monkeypatch):
    """The figures the README and the report show (about a minute)."""
    out, check = tmp_path / "out", tmp_path / "check"
    problems = _checked_run(shared_data, out, check, monkeypatch)
    assert len(list((out / "figures").glob("*.png"))) >= 29
    assert not problems, "\n".join(problems)


def test_two_labels_touching_on_one_line_are_caught(fig):
    """Two tick labels that touch read as one word ("mediumObjVel"), though their boxes do not overlap."""
    f, ax = fig
    ax.set_xticks([0, 1], ["ObjVel=medium", "ObjVel=slow"])
    ax.set_xlim(-0.5, 1.5)
    assert figure_problems(f) == []
    f.set_figwidth(1.8)  # narrower: the labels meet
    problems = figure_problems(f)
    assert any("'ObjVel=medium' and 'ObjVel=slow'" in p for p in problems), problems


# ---------------------------------------------------------------- colour alone
def _lines(ax, n, styles=None):
    for i in range(n):
        marker, ls = styles[i] if styles else ("o", "-")
        ax.plot([0, 1, 2], [i, i + 0.5, i + 0.2], marker=marker, linestyle=ls, label=f"series {i}")


def test_five_lines_told_apart_by_colour_alone_are_caught_and_four_pass(fig):
    f, ax = fig
    _lines(ax, 4)
    assert figure_problems(f) == []  # up to four series may differ by colour only
    _lines(ax, 1)
    problems = [p for p in figure_problems(f) if p.startswith("colour alone")]
    assert len(problems) == 1 and "5 series" in problems[0] and "'series 0'" in problems[0], problems


def test_five_lines_each_with_its_own_marker_or_line_style_pass(fig):
    f, ax = fig
    _lines(ax, 5, [("o", "-"), ("s", "-"), ("^", "-"), ("o", "--"), ("", "-.")])
    ax.axhline(0.5, color="grey", linestyle=":")  # a reference line is a series too: a look of its own
    assert [p for p in figure_problems(f) if p.startswith("colour alone")] == []


def test_error_bars_and_bars_count_as_one_series_each(fig):
    f, ax = fig
    for i in range(5):  # five bar sets, no hatch: colour alone
        ax.bar(np.arange(3) + i * 0.15, [1, 2, 3], width=0.15, label=f"bars {i}")
    assert any(p.startswith("colour alone: 5 series") for p in figure_problems(f))
    f2, ax2 = plt.subplots(figsize=(4, 3))
    for i, h in enumerate(["", "//", "..", "xx", "\\\\"]):
        ax2.bar(np.arange(3) + i * 0.15, [1, 2, 3], width=0.15, hatch=h, label=f"bars {i}")
    for i, m in enumerate("os^Dv"):  # error bars with caps: the caps are not series of their own
        ax2.errorbar([0, 1], [i, i], yerr=0.1, capsize=3, marker=m, label=f"err {i}")
    assert [p for p in figure_problems(f2) if p.startswith("colour alone")] == []
    plt.close(f2)


def test_a_line_and_its_band_of_one_colour_are_one_series(fig):
    f, ax = fig
    for i, ls in enumerate(["-", "--", ":", "-."]):
        ax.plot([0, 1], [i, i], linestyle=ls, color=f"C{i}")
        ax.fill_between([0, 1], [i - 0.2] * 2, [i + 0.2] * 2, color=f"C{i}", alpha=0.2)
    ax.plot([0, 1], [5, 5], marker="o", color="C4")
    assert [p for p in figure_problems(f) if p.startswith("colour alone")] == []


def test_every_fusion_strategy_has_a_look_of_its_own_besides_its_colour(fig):
    """The shared strategy look (glu.plots.style): seven strategies in one axes, as lines or as markers
    alone (the calibration bins), are never told apart by colour alone, and no two share a marker."""
    from glu.plots.style import STRATEGY_LABELS, STRATEGY_MARKERS, strategy_style

    assert set(STRATEGY_MARKERS) == set(STRATEGY_LABELS)
    assert len(set(STRATEGY_MARKERS.values())) == len(STRATEGY_MARKERS)
    f, ax = fig
    f2, ax2 = plt.subplots(figsize=(4, 3))
    for i, strategy in enumerate(STRATEGY_LABELS):
        ax.plot([0, 1, 2], [i, i + 0.3, i + 0.1], **strategy_style(strategy), label=strategy)
        style = strategy_style(strategy)
        ax2.scatter([0, 1, 2], [i, i, i], color=style["color"], marker=style["marker"], s=30)
    assert [p for p in figure_problems(f) if p.startswith("colour alone")] == []
    assert [p for p in figure_problems(f2) if p.startswith("colour alone")] == []
    plt.close(f2)


@pytest.mark.parametrize(
    "text, width",
    [
        ("uniform actions, generating network, p_HMM per-frame, raw features", 52),
        ("gesture (HMMs alone) = hard decision = Jeffrey's rule;", 52),
        ("a b c d e f g h i j k", 10),
        ("short", 52),
        ("", 52),
    ],
)
def test_a_balanced_title_keeps_every_word_within_the_width_in_as_few_lines_as_textwrap(text, width):
    import textwrap

    from glu.plots.style import balanced_fill

    plain = textwrap.wrap(text, width, break_on_hyphens=False)
    lines = balanced_fill(text, width).split("\n") if text else []
    assert " ".join(lines).split() == text.split()
    assert len(lines) == len(plain) and all(len(line) <= width for line in lines)
    if len(plain) > 1:  # as even as the words allow: the longest line no longer than textwrap's
        assert max(map(len, lines)) <= max(map(len, plain))
        assert min(map(len, lines)) >= min(map(len, plain))


def test_a_legend_reaching_into_the_next_panel_is_caught():
    f, (a, b) = plt.subplots(1, 2, figsize=(6, 3))
    a.plot([0, 1], [0, 1], label="a line")
    a.legend(loc="upper left", bbox_to_anchor=(0.9, 1))
    problems = figure_problems(f)
    plt.close(f)
    assert "text on another panel: the legend [a line] inside panel 2" in problems, problems


def test_an_annotation_at_a_data_point_outside_the_axes_is_caught(fig):
    f, ax = fig
    ax.set_xlim(0, 1)
    ax.annotate("note", xy=(1.3, 0.5), annotation_clip=False)
    assert figure_problems(f) == [
        "label across the frame: 'note', placed at a data point, is outside panel 1"
    ]


def test_a_legend_on_an_image_is_caught(fig):
    from matplotlib.patches import Patch

    f, ax = fig
    ax.imshow(np.arange(16).reshape(4, 4))
    ax.legend(handles=[Patch(color="k", label="scale")], loc="upper left")
    assert figure_problems(f) == ["legend on data: the legend [scale] covers the image of panel 1"]


def test_a_label_or_a_legend_on_scatter_markers_is_caught_and_one_on_faint_ones_passes(fig):
    f, ax = fig
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    dots = ax.scatter([0.05, 0.5], [0.95, 0.5], s=200, label="dots")
    ax.text(0.5, 0.5, "here")
    ax.legend(loc="upper left")
    assert figure_problems(f) == [
        "legend on data: the legend [dots] covers the PathCollection 'dots' of panel 1",
        "label on data: 'here' covers the PathCollection 'dots' of panel 1",
    ]
    ax.get_legend().remove()
    dots.set_alpha(0.1)  # shading a label may sit on
    assert figure_problems(f) == []


def test_what_draws_nothing_is_not_in_the_way(fig):
    """A zero-width space is no text; a bar a billionth wide and high is no patch; an axes of no width is
    crossed by no text (and its edges of length 0 give no warning)."""
    import warnings

    f, ax = fig
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.text(0.5, 0.5, "\u200b")
    ax.text(0.5, 0.5, "x", ha="center", va="center")
    ax.bar([0.5], [1e-9], width=1e-9, bottom=0.5)
    ax.set_xticks([0.5], ["a rotated tick label"], rotation=45, ha="right")
    flat = f.add_axes([0.45, 0.0, 0.0, 0.3])  # across the rotated label
    flat.set_xticks([])
    flat.set_yticks([])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert figure_problems(f) == []
