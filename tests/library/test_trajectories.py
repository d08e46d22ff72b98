"""YARP hand logs: exact loading, line-precise errors (also under fuzzing), gap/spike/jump detection and
repair."""

from __future__ import annotations

import numpy as np
import pytest
from cli_run import train_recogniser
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from glu.data.recordings import RECORDING_ACTION
from glu.errors import DataError
from glu.gestures.recordings import parse_hand_log, read_hand_log
from glu.gestures.trajectories import (
    DETECT_ONLY,
    RepairPolicy,
    Trajectory,
    repair,
    summarize_events,
)

GOOD = (
    "-1 1495933414.180140 644.291918 -809.62949 -934.764515\n"
    "-1 1495933414.207243 652.562922 -805.78474 -929.717833\n"
    "\n"
    "7 1495933414.242088 648.199463 -790.254477 -931.142356\r\n"
)


def test_parse_keeps_timestamps_and_values_exactly():
    tr = parse_hand_log(GOOD, source="x.log")
    assert len(tr) == 3
    assert tr.t.tolist() == [1495933414.180140, 1495933414.207243, 1495933414.242088]
    assert tr.xyz[0].tolist() == [644.291918, -809.62949, -934.764515]
    assert tr.xyz[2].tolist() == [648.199463, -790.254477, -931.142356]
    assert tr.frame.tolist() == [1, 2, 3]  # the blank line is not a frame
    assert tr.observed.all()


@pytest.mark.parametrize(
    "bad_line, fragment",
    [
        ("-1 1495933414.3 1.0 2.0", "expected 5 fields"),
        ("-1 1495933414.3 1.0 2.0 3.0 4.0", "expected 5 fields"),
        ("-1 1495933414.3 1.0 abc 3.0", "y 'abc' is not a finite number"),
        ("-1 1495933414.3 1.0 nan 3.0", "is not a finite number"),
        ("-1 1495933414.3 inf 2.0 3.0", "is not a finite number"),
        ("-1 1495933414.3 1_000 2.0 3.0", "is not a finite number"),
        ("-1 1495933414.3 1e157 2.0 3.0", "17: x '1e157' is outside ±10,000"),  # finite, but no hand is there
        ("-1 1495933414.3 1.0 2.0 -10000.5", "25: z '-10000.5' is outside ±10,000"),
        ("x 1495933414.3 1.0 2.0 3.0", "index 'x' is not an integer"),
        ("-1 1495933414.0 1.0 2.0 3.0", "does not increase"),
    ],
)
def test_malformed_line_gives_file_and_line(bad_line, fragment):
    text = GOOD + bad_line + "\n"
    with pytest.raises(DataError) as e:
        parse_hand_log(text, source="rec/data.log")
    msg = str(e.value)
    assert msg.startswith("rec/data.log:5:"), msg
    assert fragment in msg


def test_the_physical_range_lets_every_published_value_through():
    from glu.data.hand_logs import MAX_LOGGED_COORDINATE

    ok = GOOD + f"-1 1495933415.0 {MAX_LOGGED_COORDINATE} -{MAX_LOGGED_COORDINATE} 2297.08\n"
    assert parse_hand_log(ok, source="f").xyz[-1].tolist() == [
        MAX_LOGGED_COORDINATE,
        -MAX_LOGGED_COORDINATE,
        2297.08,
    ]


def test_a_huge_coordinate_is_refused_by_recognize_not_turned_into_nan(tmp_path, capsys):
    from glu.cli import main

    log = tmp_path / "huge.log"
    log.write_text(GOOD + "-1 1495933415.0 1e157 2.0 3.0\n" + "-1 1495933415.1 1.0 2.0 3.0\n")
    models = tmp_path / "r.json"
    train_recogniser(models)
    capsys.readouterr()
    assert main(["recognize", str(log), "--models", str(models), "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and "Traceback" not in err and "nan" not in err.lower()
    assert err.splitlines()[-1].startswith(f"glu recognize: error: {log}:5:17: x '1e157' is outside ±10,000")


def test_non_ascii_and_other_encodings_are_data_errors():
    latin = (GOOD + "-1 1495933415.0 1.0 2.0 3.0 é\n").encode("latin-1")
    with pytest.raises(DataError, match=r"^f:5: byte 0xe9 at column 29 is not ASCII"):
        parse_hand_log(latin, source="f")
    with pytest.raises(DataError, match=r"^f:1: .*not ASCII"):
        parse_hand_log(GOOD.encode("utf-16"), source="f")


def test_empty_missing_and_folder(tmp_path):
    with pytest.raises(DataError, match="no frames"):
        parse_hand_log("\n\n", source="f")
    with pytest.raises(DataError, match="no such file"):
        read_hand_log(tmp_path / "nope.log")
    with pytest.raises(DataError, match="no such file"):
        read_hand_log(tmp_path)  # a folder without data.log
    (tmp_path / "rec" / "data.log").mkdir(parents=True)
    with pytest.raises(DataError, match=r"data.log: cannot read: Is a directory"):
        read_hand_log(tmp_path / "rec")  # a recording folder whose data.log is a folder
    (tmp_path / "data.log").write_text(GOOD)
    assert len(read_hand_log(tmp_path)) == 3  # a recording folder is accepted


# --- fuzzing: whatever the bytes, a DataError or a trajectory, nothing else ---------------------------


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=300))
def test_fuzz_arbitrary_bytes(data):
    try:
        tr = parse_hand_log(data, source="fuzz")
    except DataError as e:
        assert str(e).startswith("fuzz")
    else:
        assert isinstance(tr, Trajectory) and len(tr) >= 1
        assert np.all(np.isfinite(tr.xyz)) and np.all(np.diff(tr.t) > 0)


_line = st.tuples(
    st.integers(-5, 10**6),
    st.floats(-1e4, 1e4),
    st.floats(-1e4, 1e4),
    st.floats(-1e4, 1e4),  # a hand's range
).map(lambda v: f"{v[0]} {{t}} {v[1]!r} {v[2]!r} {v[3]!r}")


@settings(max_examples=150, deadline=None)
@given(
    lines=st.lists(_line, min_size=1, max_size=8),
    where=st.integers(0, 7),
    damage=st.sampled_from(["truncate", "junk", "latin1", "utf16", "tab-junk"]),
    cut=st.integers(0, 200),
)
def test_fuzz_one_damaged_line_is_reported_at_its_line(lines, where, damage, cut):
    text_lines = [ln.format(t=1000.0 + 0.033 * i) for i, ln in enumerate(lines)]
    k = where % len(text_lines)
    line = text_lines[k]
    if damage == "truncate":  # cut inside the first four fields: never five fields
        fourth_field_end = len(" ".join(line.split()[:4]))
        text_lines[k] = line[: cut % (fourth_field_end + 1)]
        if not text_lines[k].strip():
            text_lines[k] = "1"
    elif damage == "junk":
        text_lines[k] = line + " #junk"
    elif damage == "tab-junk":
        text_lines[k] = line.replace(" ", "\t", 1) + "\tx"
    data = "\n".join(text_lines).encode("ascii")
    if damage == "latin1":
        data = "\n".join(text_lines[:k] + [line + " °C"] + text_lines[k + 1 :]).encode("latin-1")
    elif damage == "utf16":
        data = "\n".join(text_lines).encode("utf-16-le")
        k = 0  # the first line already holds NUL bytes
    with pytest.raises(DataError) as e:
        parse_hand_log(data, source="log")
    assert str(e.value).startswith(f"log:{k + 1}:"), str(e.value)


# --- the logs of a data folder ------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(RECORDING_ACTION))
def test_logs_load_like_loadtxt(source, name):
    path = source.hand_log(name)
    ref = np.loadtxt(path)  # an independent parser
    tr = read_hand_log(path)
    assert len(tr) == len(ref) == len(path.read_text().splitlines())
    np.testing.assert_array_equal(tr.t, ref[:, 1])
    np.testing.assert_array_equal(tr.xyz, ref[:, 2:])


def test_written_logs_read_back_exactly(tmp_path):
    from glu.data.hand_logs import format_hand_log, write_hand_log

    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.02, 0.05, 50)).round(6)
    xyz = rng.normal(scale=500, size=(50, 3)).round(6)
    tr = read_hand_log(write_hand_log(tmp_path / "rec", t, xyz))
    np.testing.assert_array_equal(tr.t, t)
    np.testing.assert_array_equal(tr.xyz, xyz)
    with pytest.raises(DataError, match="strictly increasing"):
        format_hand_log(t[::-1], xyz)
    for bad_t, bad_xyz in ((t, xyz[:, :2]), (t[:0], xyz[:0])):
        with pytest.raises(DataError, match=r"n ≥ 1 timestamps and \(n, 3\) coordinates"):
            format_hand_log(bad_t, bad_xyz)


# --- repair on constructed trajectories ------------------------------------------------------------


def _line_traj(n=60, period=1 / 30):
    t = np.arange(n) * period
    xyz = np.stack([t, 2 * t, -t], axis=1)  # a straight line at constant speed
    return Trajectory(xyz, t, np.arange(1, n + 1), np.ones(n, dtype=bool), "line")


def test_short_gap_is_interpolated_linearly_at_the_frame_period():
    tr = _line_traj()
    keep = np.ones(60, dtype=bool)
    keep[20:26] = False  # 6 frames lost: a 0.233 s gap
    rp = repair(tr.take(keep))
    assert len(rp.pieces) == 1
    p = rp.pieces[0]
    assert len(p) == 60
    np.testing.assert_allclose(p.xyz, tr.xyz, atol=1e-12)  # linear motion is restored exactly
    np.testing.assert_allclose(p.t, tr.t, atol=1e-12)
    assert (~p.observed).sum() == 6 and not p.observed[20:26].any()
    assert p.frame[20:26].tolist() == [20] * 6  # inserted frames carry the last observed frame number
    (gap,) = [e for e in rp.events if e.kind == "gap"]
    assert gap.frame == 27 and gap.action == "interpolated" and gap.size == pytest.approx(7 / 30)


def test_long_gap_splits_or_is_kept():
    tr = _line_traj(90)
    keep = np.ones(90, dtype=bool)
    keep[30:60] = False  # 1 s lost
    rp = repair(tr.take(keep))
    assert [(int(p.frame[0]), int(p.frame[-1])) for p in rp.pieces] == [(1, 30), (61, 90)]
    kept = repair(tr.take(keep), RepairPolicy(long_gaps="keep"))
    assert len(kept.pieces) == 1 and len(kept.pieces[0]) == 60
    everything = repair(tr.take(keep), RepairPolicy(max_interpolate=float("inf")))
    assert len(everything.pieces[0]) == 90


def test_spike_is_found_and_replaced_dropped_or_kept():
    tr = _line_traj()
    xyz = tr.xyz.copy()
    xyz[33] += [0.0, 0.8, 0.0]
    spiky = tr.with_xyz(xyz)
    rp = repair(spiky)
    (sp,) = [e for e in rp.events if e.kind == "spike"]
    assert sp.frame == 34 and sp.action == "replaced" and sp.size == pytest.approx(0.8, rel=0.1)
    np.testing.assert_allclose(rp.pieces[0].xyz, tr.xyz, atol=1e-12)
    assert not rp.pieces[0].observed[33]
    assert len(repair(spiky, RepairPolicy(spikes="drop")).pieces[0]) == 59
    np.testing.assert_array_equal(repair(spiky, RepairPolicy(spikes="keep")).pieces[0].xyz, xyz)
    assert not [e for e in repair(tr).events if e.kind == "spike"]  # fast straight motion is no spike


def test_jump_is_reported_and_left_alone():
    tr = _line_traj()
    xyz = tr.xyz.copy()
    xyz[40:] += [1.0, 0.0, 0.0]  # a persistent displacement: not a spike
    rp = repair(tr.with_xyz(xyz))
    (jump,) = [e for e in rp.events if e.kind == "jump"]
    assert jump.frame == 41 and jump.action == "kept"
    np.testing.assert_array_equal(rp.pieces[0].xyz, xyz)
    assert "1 jump (1 kept)" in summarize_events(rp.events)


def test_missing_coordinates_become_a_gap():
    tr = _line_traj()
    xyz = tr.xyz.copy()
    xyz[10:13] = np.nan
    rp = repair(tr.with_xyz(xyz))
    assert [e.frame for e in rp.events if e.kind == "missing"] == [11, 12, 13]
    np.testing.assert_allclose(rp.pieces[0].xyz, tr.xyz, atol=1e-12)


def test_detect_only_changes_nothing():
    tr = _line_traj()
    xyz = tr.xyz.copy()
    xyz[5] += 5.0
    keep = np.ones(60, dtype=bool)
    keep[30:50] = False
    src = tr.with_xyz(xyz).take(keep)
    rp = repair(src, DETECT_ONLY)
    assert len(rp.pieces) == 1
    np.testing.assert_array_equal(rp.pieces[0].xyz, src.xyz)
    assert {e.kind for e in rp.events} == {"spike", "gap", "jump"}


def test_frames_selects_source_numbers_and_rejects_bad_ranges():
    tr = _line_traj()
    sel = tr.frames(10, 12)
    assert sel.frame.tolist() == [10, 11, 12]
    np.testing.assert_array_equal(sel.xyz, tr.xyz[9:12])
    for bad in [(0, 5), (5, 61), (20, 10)]:
        with pytest.raises(DataError, match="out of range; allowed: 1 ≤ first ≤ last ≤ 60"):
            tr.frames(*bad)


def test_policy_validation():
    with pytest.raises(DataError, match="allowed"):
        RepairPolicy(spikes="smooth")
    with pytest.raises(DataError, match="odd"):
        RepairPolicy(spike_window=4)


def test_each_tracking_event_describes_itself_in_one_line():
    from glu.gestures.trajectories import TrackingEvent

    said = [
        TrackingEvent("gap", 339, 10.3149, 1.538, "split").describe(),
        TrackingEvent("spike", 12, 0.4, 0.25, "replaced").describe(),
        TrackingEvent("jump", 40, 1.3, 0.612, "kept").describe(),
        TrackingEvent("short-piece", 400, 13.0, 7.0, "dropped").describe(),
        TrackingEvent("missing", 5, 0.13, 0.0, "dropped").describe(),
    ]
    assert said == [
        "gap of 1.54 s before frame 339 (t=10.31 s): split",
        "spike at frame 12 (0.25 from the running median) (t=0.40 s): replaced",
        "jump of 0.61 before frame 40 (t=1.30 s): kept",
        "piece of 7 frames from frame 400 (t=13.00 s): dropped",
        "missing at frame 5 (t=0.13 s): dropped",
    ]


def test_a_trajectory_checks_its_arrays():
    t = np.arange(4) / 30
    with pytest.raises(
        DataError, match=r"mine: xyz must have shape \(n_frames, 3\) = \(4, 3\), got \(4, 2\)"
    ):
        Trajectory(np.zeros((4, 2)), t, np.arange(1, 5), np.ones(4, bool), "mine")
    with pytest.raises(DataError, match="mine: timestamps must be finite and strictly increasing"):
        Trajectory(np.zeros((4, 3)), t[::-1], np.arange(1, 5), np.ones(4, bool), "mine")
    with pytest.raises(DataError, match=r"mine: frame and observed must have shape \(4,\)"):
        Trajectory(np.zeros((4, 3)), t, np.arange(1, 4), np.ones(4, bool), "mine")
    empty = Trajectory(np.zeros((0, 3)), t[:0], np.arange(0), np.ones(0, bool), "mine")
    with pytest.raises(DataError, match="mine: the trajectory has no frames"):
        empty.frames(1, 1)


def test_a_trajectory_without_a_finite_frame_cannot_be_repaired():
    tr = _line_traj(10)
    with pytest.raises(DataError, match="line: no frame has finite coordinates"):
        repair(tr.with_xyz(np.full((10, 3), np.nan)))


def test_more_policy_validation():
    with pytest.raises(DataError, match="long_gaps='drop'; allowed: 'split', 'keep'"):
        RepairPolicy(long_gaps="drop")
    for bad in ({"gap_factor": 1.0}, {"max_interpolate": -1.0}, {"min_piece": 0}):
        with pytest.raises(DataError, match="gap_factor must be > 1, max_interpolate ≥ 0 and min_piece ≥ 1"):
            RepairPolicy(**bad)


def test_repaired_many_takes_changes_to_the_policy_and_checks_its_arguments():
    from glu.gestures.trajectories import repaired_many, repaired_xyz

    tr = _line_traj(40)
    keep = np.ones(40, dtype=bool)
    keep[10:25] = False  # a long gap: two pieces of 10 and 15 frames
    src = tr.take(keep)
    assert len(repaired_many([src.xyz], [src.t])[0]) == 25
    strict = repaired_many([src.xyz], [src.t], min_piece=12)[0]
    np.testing.assert_array_equal(strict, src.xyz[10:])  # the first piece is too short now
    np.testing.assert_array_equal(strict, repaired_xyz(src.xyz, src.t, RepairPolicy(min_piece=12)))
    assert repaired_many([], []) == []
    with pytest.raises(DataError, match="2 coordinate arrays but 1 timestamp arrays"):
        repaired_many([src.xyz, src.xyz], [src.t])
