"""Segments: the originals' ranges, automatic segmentation against known truth, the segmentation figure."""

from __future__ import annotations

import io
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from glu.errors import DataError  # noqa: E402
from glu.gestures.corpus import (  # noqa: E402
    ORIGINAL_SEGMENTS,
    TRAINING_RECORDINGS,
    original_segments,
    real_segments,
    segment_recording_of,
)
from glu.gestures.recordings import segment_recording  # noqa: E402
from glu.gestures.segmentation import Segment, extract, segment_repetitions  # noqa: E402
from glu.gestures.synthetic import GESTURES, synthesize_recording  # noqa: E402
from glu.gestures.trajectories import Trajectory, repair  # noqa: E402
from glu.studies.replication.gesture_figures import plot_segmentation  # noqa: E402


def _iou(a: tuple[int, int], b: tuple[int, int]) -> float:
    inter = max(0, min(a[1], b[1]) - max(a[0], b[0]) + 1)
    return inter / (max(a[1], b[1]) - min(a[0], b[0]) + 1)


def _features(rec) -> Trajectory:
    return rec.trajectory()


def test_original_ranges_are_those_of_the_papers():
    assert ORIGINAL_SEGMENTS == {
        "tap1_hand": ((216, 351), (401, 511), (557, 664)),
        "tap_notable_seated_1": ((121, 214),),
        "norobotview_tap_notable_seated_2": ((230, 375),),
    }
    assert [s.label for s in original_segments("tap1_hand")] == ["tap"] * 3
    assert original_segments("grasp1_hand") == []


@pytest.mark.parametrize("action", GESTURES)
@pytest.mark.parametrize("seed", [0, 1])
def test_automatic_segmentation_finds_the_true_repetitions(action, seed):
    rec = synthesize_recording(action, 4, seed=seed, noise=0.01, spike_rate=0.005)
    (piece,) = repair(_features(rec)).pieces
    seg = segment_repetitions(piece, label=action)
    found = [(s.start, s.end) for s in seg.segments]
    assert len(found) == len(rec.segments) == 4, (found, rec.segments)
    for f, (a, b) in zip(found, rec.segments, strict=True):
        # inside the true movement (± 5 frames), covering most of it: its first and last frames are
        # minimum-jerk slow, within the sensor noise of the rest pose
        assert a - 5 <= f[0] <= f[1] <= b + 5, (f, (a, b))
        assert (min(f[1], b) - max(f[0], a) + 1) / (b - a + 1) > 0.7, (f, (a, b))
    assert all(s.label == action for s in seg.segments)


def test_a_repetition_cut_by_the_end_is_partial():
    rec = synthesize_recording("tap", 3, seed=2, noise=0.005)
    a, b = rec.segments[-1]
    cut = _features(rec).take(slice(0, (a + b) // 2))  # stop in the middle of the last repetition
    seg = segment_repetitions(cut)
    assert len(seg.segments) == 2
    assert any("partial" in why for _, why in seg.rejected)


def test_extract_and_bad_input():
    rec = synthesize_recording("push", 2, seed=0)
    tr = _features(rec)
    s = Segment(*rec.segments[0])
    np.testing.assert_array_equal(extract(tr, s), tr.xyz[s.start - 1 : s.end])
    with pytest.raises(DataError, match="no frame"):
        extract(tr, Segment(10**6, 10**6 + 5))
    with pytest.raises(DataError, match="cannot be segmented"):
        segment_repetitions(tr.take(slice(0, 1)))


def test_a_segment_with_a_tracking_jump_is_left_out():
    """Every step between frames is longer than max_jump = 0: each repetition is left out for its longest
    step, which is measured here on the segment's own frames."""
    from glu.gestures.segmentation import SegmentationParams

    tr = _features(synthesize_recording("push", 2, seed=0))
    seg = segment_repetitions(tr, params=SegmentationParams(max_jump=0.0))
    assert seg.segments == [] and len(seg.rejected) == 2
    for s, why in seg.rejected:
        longest = np.linalg.norm(np.diff(tr.xyz[s.start - 1 : s.end], axis=0), axis=1).max()
        assert why == f"tracking jump of {longest:.2f} (more than 0.0)"


def _png(seg, ref=()) -> tuple[bytes, int]:
    fig, ax = plt.subplots(figsize=(8, 3))
    plot_segmentation(ax, seg, "title", reference=ref)
    n_spans = len(ax.patches)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue(), n_spans


def test_plot_is_deterministic_and_shows_every_segment():
    rec = synthesize_recording("touch", 3, seed=4)
    seg = segment_repetitions(repair(_features(rec)).pieces[0])
    png1, spans = _png(seg)
    png2, _ = _png(seg)
    assert png1 == png2
    assert spans == len(seg.segments) + len(seg.rejected)


# --- the recordings of a data folder (synthetic look-alikes, and the real ones when present) ----------


def test_tap1_repetitions_match_the_originals_hand_cut_segments(source):
    seg = segment_recording_of(source, "tap1_hand")
    found = [(s.start, s.end) for s in seg.segments]
    assert len(found) == 3
    # the hand-cut ranges hold the taps (in the real log, and at the synthetic look-alike's placements)
    for f, (a, b) in zip(found, ORIGINAL_SEGMENTS["tap1_hand"], strict=True):
        assert _iou(f, (a, b)) > 0.75, (f, (a, b))


@pytest.mark.parametrize("name", TRAINING_RECORDINGS)
def test_recordings_yield_labelled_segments(source, name):
    seg = segment_recording_of(source, name)
    assert len(seg.segments) >= 2
    n = len(np.loadtxt(source.hand_log(name)))
    prev_end = 0
    for s in seg.segments:
        assert s.label == name.split("1_")[0]
        assert prev_end < s.start <= s.end <= n  # ordered, disjoint, within the log
        assert s.n_frames >= 45
        prev_end = s.end


def test_segments_for_training(source):
    seqs = real_segments(source)
    actions = {s.action for s in seqs}
    assert actions == {"grasp", "tap", "touch", "push"}
    singles = [(s.recording, s.start, s.end) for s in seqs if s.recording.startswith(("tap_", "norobot"))]
    assert singles == [("tap_notable_seated_1", 121, 214), ("norobotview_tap_notable_seated_2", 230, 375)]
    for s in seqs:
        assert (
            s.xyz.shape[1] == 3 and len(s.xyz) >= s.end - s.start + 1
        )  # interpolated frames add, never remove
        assert np.abs(s.xyz).max() < 5  # feature units, not the log's millimetre-like values


def test_plot_a_recording(source):
    seg = segment_recording(source.hand_log("push1_hand"))
    png1, _ = _png(seg, original_segments("push1_hand"))
    png2, _ = _png(seg, original_segments("push1_hand"))
    assert png1 == png2 and png1[:8] == b"\x89PNG\r\n\x1a\n"


def test_hand_cut_segments_outside_a_shortened_recording_are_left_out(synthetic_folder, tmp_path):
    import shutil

    from glu.data import resolve_data

    root = tmp_path / "data"
    shutil.copytree(synthetic_folder, root)
    log = root / "gestures" / "tap1_hand" / "data.log"
    log.write_text("".join(log.read_text().splitlines(keepends=True)[:400]))  # frames 1 … 400
    source = resolve_data(root)
    seqs = [s for s in real_segments(source, recordings=()) if s.recording == "tap1_hand"]
    assert [(s.start, s.end) for s in seqs] == [ORIGINAL_SEGMENTS["tap1_hand"][0]]  # (216, 351) only


# ---------------------------------------------------------------- your own labelled recordings
def _table(path, n=30, x=0.1):
    path.parent.mkdir(parents=True, exist_ok=True)
    t = np.arange(n) / 30.0
    rows = np.column_stack([t, np.full(n, x), np.linspace(-0.2, 0.1, n), np.full(n, -0.3)])
    np.savetxt(path, rows, delimiter=",", header="t,x,y,z", comments="")
    return path


def test_labelled_folders_take_recording_folders_and_skip_hidden_files(tmp_path):
    from glu.gestures.corpus import labelled_recordings

    root = tmp_path / "mine"
    _table(root / "wave" / "a.csv")
    (root / "wave" / "b").mkdir()
    (root / "wave" / "b" / "data.log").write_text(
        "".join(f"{i} {i / 30:.6f} 100 -200 -300\n" for i in range(20))
    )
    (root / "wave" / ".notes.csv").write_text("not a recording")
    corpus = labelled_recordings(root)
    assert [(s.action, s.recording, len(s.xyz)) for s in corpus] == [
        ("wave", "wave/a.csv", 30),
        ("wave", "wave/b/data.log", 20),
    ]
    np.testing.assert_allclose(corpus[1].xyz[0], [0.1, -0.2, -0.3])  # logged units / 1000


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("file,label,frames,who\n", "columns must be file, label, frames; got file, label, frames, who"),
        ("file,label,when\n", "columns must be file, label, frames; got file, label, when"),
        ("file,label\n,wave\n", "m.csv, line 2: empty file or label"),
        ("file,label\nwave/a.csv, \n", "m.csv, line 2: empty file or label"),
        (b"file,label\n\xff\n", "m.csv: cannot read the manifest"),
    ],
)
def test_more_bad_manifests(tmp_path, content, message):
    from glu.gestures.corpus import labelled_recordings

    _table(tmp_path / "wave" / "a.csv")
    manifest = tmp_path / "m.csv"
    manifest.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(DataError, match=re.escape(message)):
        labelled_recordings(manifest)


def test_a_manifest_may_skip_blank_rows_and_name_a_recording_folder(tmp_path):
    from glu.gestures.corpus import labelled_recordings

    _table(tmp_path / "recs" / "a.csv")
    (tmp_path / "recs" / "b").mkdir()
    (tmp_path / "recs" / "b" / "data.log").write_text("".join(f"{i} {i / 30:.6f} 1 2 3\n" for i in range(12)))
    (tmp_path / "m.csv").write_text("file,label\nrecs/a.csv,wave\n,\n\nrecs/b,point\n")
    corpus = labelled_recordings(tmp_path / "m.csv")
    assert [(s.action, s.recording, len(s.xyz)) for s in corpus] == [
        ("wave", "recs/a.csv", 30),
        ("point", "recs/b/data.log", 12),
    ]
    with pytest.raises(DataError, match="nowhere: no such folder or manifest"):
        labelled_recordings(tmp_path / "nowhere")


def test_an_empty_trajectory_has_no_activity_to_segment():
    from glu.gestures.segmentation import activity_signal

    with pytest.raises(DataError, match="^cannot segment an empty trajectory$"):
        activity_signal(np.zeros((0, 3)))
